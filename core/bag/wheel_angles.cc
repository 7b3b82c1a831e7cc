#include <calib/core/bag/encoder_messages.h>
#include <calib/core/bag/message_definition.h>
#include <calib/core/bag/wheel_angles.h>
#include <calib/core/laser/wheel_readings.h>
#include <calib/core/se2.h>
#include <calib/core/text_number.h>

#include <algorithm>
#include <cmath>

namespace calib {
namespace {

double MessageTime(double stamp_s, double log_time_s) {
  return stamp_s > 0.0 ? stamp_s : log_time_s;
}

int IndexOf(const std::vector<std::string>& names, const std::string& name) {
  const auto it = std::find(names.begin(), names.end(), name);
  return it == names.end() ? -1 : static_cast<int>(it - names.begin());
}

// Adds whole turns where a joint reported wrapped (UnwrapWheelAngles) jumps between samples.
int Unwrap(std::vector<EncoderSample>* samples, double EncoderSample::*angle) {
  std::vector<double> angles;
  for (const EncoderSample& s : *samples) angles.push_back(s.*angle);
  const int turns = UnwrapWheelAngles(&angles, 1, 0);
  for (size_t k = 0; k < angles.size(); ++k) (*samples)[k].*angle = angles[k];
  return turns;
}

double Yaw(const Eigen::Quaterniond& q) {
  return std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()),
                    1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
}

// Signed arc length of a step from (x, y, yaw) a to b taken as one arc: the chord over
// sinc(Δθ/2), forward when the chord points along the mid-step heading.
double ArcLength(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const double turn = WrapAngle(b(2) - a(2));
  const double dx = b(0) - a(0), dy = b(1) - a(1);
  const double chord = std::hypot(dx, dy);
  const double heading = a(2) + 0.5 * turn;
  const double along = dx * std::cos(heading) + dy * std::sin(heading);
  const double half = 0.5 * turn;
  const double arc = std::abs(half) > 1e-9 ? chord * half / std::sin(half) : chord;
  return along < 0.0 ? -arc : arc;
}

}  // namespace

StatusOr<WheelAngleStream> WheelAnglesFromJointStates(const std::vector<JointState>& messages,
                                                      const std::string& left_joint,
                                                      const std::string& right_joint,
                                                      const std::string& where,
                                                      double radians_per_unit) {
  if (!(radians_per_unit > 0.0) || !std::isfinite(radians_per_unit)) {
    return Status::InvalidInput(where +
                                ": the wheel angles' unit must be a positive number of "
                                "radians");
  }
  WheelAngleStream out;
  std::vector<std::pair<double, double>> speeds_rad_s;  // With from_velocities: per sample.
  for (const JointState& m : messages) {
    const int left = IndexOf(m.name, left_joint), right = IndexOf(m.name, right_joint);
    if (left < 0 && right < 0) {
      ++out.skipped_messages;
      continue;
    }
    if (left < 0 || right < 0) {
      ++out.half_messages;
      continue;
    }
    const std::string record = where + ": record " + std::to_string(m.record);
    const bool speeds = m.position.empty() && m.velocity.size() == m.name.size();
    if (m.position.size() != m.name.size() && !speeds) {
      return Status::InvalidInput(record + ": JointState has " + std::to_string(m.name.size()) +
                                  " names but " + std::to_string(m.position.size()) +
                                  " positions (and " + std::to_string(m.velocity.size()) +
                                  " velocities): the wheel angles need positions, or velocities");
    }
    if (!out.samples.empty() && speeds != out.from_velocities) {
      return Status::InvalidInput(
          record + ": JointState carries " + (speeds ? "velocities only" : "positions") +
          " where the messages before it carried " + (speeds ? "positions" : "velocities only") +
          ": the wheel angles come from one or the other");
    }
    out.from_velocities = speeds;
    const std::vector<double>& values = speeds ? m.velocity : m.position;
    const double l = values[left] * radians_per_unit, r = values[right] * radians_per_unit;
    if (!std::isfinite(l) || !std::isfinite(r)) {
      return Status::InvalidInput(record + ": wheel joint " + (speeds ? "velocity" : "position") +
                                  " is not finite");
    }
    const double t = MessageTime(m.stamp_s, m.log_time_s);
    if (speeds) {  // Angles by trapezoids; speeds[k] keeps each sample's velocities.
      out.samples.push_back(EncoderSample{t, 0.0, 0.0, static_cast<int>(m.record)});
      speeds_rad_s.emplace_back(l, r);
      if (out.samples.size() > 1) {
        const EncoderSample& before = out.samples[out.samples.size() - 2];
        const double dt = t - before.t_s;
        if (!(dt >= 0.0)) {
          return Status::InvalidInput(record + ": its stamp is " + Num(-dt) +
                                      " s before the previous message's: velocities cannot be "
                                      "integrated backwards");
        }
        const auto& v0 = speeds_rad_s[speeds_rad_s.size() - 2];
        out.samples.back().left_rad = before.left_rad + 0.5 * dt * (v0.first + l);
        out.samples.back().right_rad = before.right_rad + 0.5 * dt * (v0.second + r);
      }
      continue;
    }
    out.samples.push_back(EncoderSample{t, l, r, static_cast<int>(m.record)});
  }
  if (out.samples.size() < 2) {
    return Status::InvalidInput(where + ": " + std::to_string(out.samples.size()) +
                                " JointState message(s) carry both '" + left_joint + "' and '" +
                                right_joint + "' (" + std::to_string(out.half_messages) +
                                " carry one of them): at least two are needed");
  }
  if (out.from_velocities) return out;  // Integrated angles are never wrapped.
  out.unwrapped_turns = Unwrap(&out.samples, &EncoderSample::left_rad) +
                        Unwrap(&out.samples, &EncoderSample::right_rad);
  return out;
}

namespace {

// The range of an integer counter of type `type` ("uint16", "int32"), 0 for one that never wraps
// in a robot's life (64 bits) or is no integer.
double CounterRange(const std::string& type) {
  for (const int bits : {8, 16, 32}) {
    const std::string width = std::to_string(bits);
    if (type == "int" + width || type == "uint" + width) return std::ldexp(1.0, bits);
  }
  return 0.0;
}

// The definition of `topic`'s type: the bag's, else calib's own for a known encoder type.
StatusOr<MessageDefinition> DefinitionOf(const RawTopic& topic, const std::string& where) {
  std::string text = topic.definition;
  const EncoderMessageType* known = FindEncoderMessageType(topic.type);
  if (text.empty() && topic.cdr && known != nullptr) text = known->Ros2Definition();
  if (text.empty()) {
    return Status::InvalidInput(where + ": the bag stores no definition of " + topic.type +
                                " (rosbag2's sqlite3 storage before Jazzy stores none), and calib "
                                "knows no such encoder message");
  }
  StatusOr<MessageDefinition> parsed =
      MessageDefinition::Parse(topic.type, text, topic.cdr ? WireFormat::kCdr : WireFormat::kRos1);
  if (!parsed.ok()) return parsed.status().Prefixed(where + ": ");
  return parsed;
}

}  // namespace

StatusOr<WheelAngleStream> WheelAnglesFromEncoderTopic(const RawTopic& topic,
                                                       const std::string& left_field,
                                                       const std::string& right_field,
                                                       const std::string& where,
                                                       double radians_per_tick) {
  if (!(radians_per_tick > 0.0) || !std::isfinite(radians_per_tick)) {
    return Status::InvalidInput(where + ": the encoder counts need the counts per wheel turn");
  }
  CALIB_ASSIGN_OR_RETURN(const MessageDefinition definition, DefinitionOf(topic, where));
  double range[2];
  const std::string* fields[2] = {&left_field, &right_field};
  for (int side = 0; side < 2; ++side) {
    const StatusOr<std::string> type = definition.FieldType(*fields[side]);
    if (!type.ok()) return type.status().Prefixed(where + ": ");
    range[side] = CounterRange(*type);
  }
  std::vector<std::string> paths = {left_field, right_field};
  if (definition.has_header()) paths.push_back("header.stamp");
  StatusOr<MessageDefinition::ResolvedPaths> resolved = definition.Resolve(paths);
  if (!resolved.ok()) return resolved.status().Prefixed(where + ": ");
  WheelAngleStream out;
  double previous[2] = {0.0, 0.0}, angle[2] = {0.0, 0.0};
  std::vector<double> values;
  for (const RawMessage& m : topic.messages) {
    const Status read = definition.ReadNumbers(m.data.data(), m.data.size(), *resolved, &values);
    if (!read.ok()) return read.Prefixed(where + ": record " + std::to_string(m.record) + ": ");
    for (int side = 0; side < 2; ++side) {
      const double count = values[side];
      if (!std::isfinite(count)) {
        return Status::InvalidInput(where + ": record " + std::to_string(m.record) +
                                    ": a count is not finite");
      }
      double step = out.samples.empty() ? count : count - previous[side];
      if (!out.samples.empty() && range[side] > 0.0 && std::abs(step) > 0.5 * range[side]) {
        step -= std::copysign(range[side], step);
        ++out.counter_wraps;
      }
      angle[side] += step * radians_per_tick;
      previous[side] = count;
    }
    const double stamp_s = paths.size() > 2 ? values[2] : 0.0;
    out.samples.push_back(EncoderSample{MessageTime(stamp_s, m.log_time_s), angle[0], angle[1],
                                        static_cast<int>(m.record)});
  }
  if (out.samples.size() < 2) {
    return Status::InvalidInput(where + ": " + std::to_string(out.samples.size()) +
                                " encoder message(s): at least two are needed");
  }
  return out;
}

StatusOr<WheelAngleStream> WheelAnglesFromOdometry(const std::vector<Odometry>& messages,
                                                   double nominal_wheel_radius_m,
                                                   double nominal_wheelbase_m,
                                                   const std::string& where) {
  if (!(nominal_wheel_radius_m > 0.0) || !(nominal_wheelbase_m > 0.0) ||
      !std::isfinite(nominal_wheel_radius_m) || !std::isfinite(nominal_wheelbase_m)) {
    return Status::InvalidInput(where +
                                ": wheel angles from Odometry need the nominal wheel "
                                "radius and wheelbase the driver used (both > 0)");
  }
  if (messages.size() < 2) {
    return Status::InvalidInput(where + ": " + std::to_string(messages.size()) +
                                " Odometry message(s): at least two are needed");
  }
  bool poses = false;
  for (const Odometry& m : messages) {
    poses = poses || m.position.head<2>().norm() > 0.0 || std::abs(Yaw(m.orientation)) > 0.0;
  }
  WheelAngleStream out;
  const double r = nominal_wheel_radius_m, half_b = 0.5 * nominal_wheelbase_m;
  double left = 0.0, right = 0.0;
  for (size_t k = 0; k < messages.size(); ++k) {
    const Odometry& m = messages[k];
    const std::string record = where + ": record " + std::to_string(m.record);
    if (!m.position.allFinite() || !m.orientation.coeffs().allFinite() ||
        !m.linear_velocity.allFinite() || !m.angular_velocity.allFinite()) {
      return Status::InvalidInput(record + ": Odometry holds a value that is not finite");
    }
    const double t = MessageTime(m.stamp_s, m.log_time_s);
    if (k > 0) {
      const Odometry& p = messages[k - 1];
      double arc = 0.0, turn = 0.0;
      if (poses) {
        const Eigen::Vector3d a(p.position.x(), p.position.y(), Yaw(p.orientation));
        const Eigen::Vector3d b(m.position.x(), m.position.y(), Yaw(m.orientation));
        arc = ArcLength(a, b);
        turn = WrapAngle(b(2) - a(2));
      } else {
        const double dt = t - MessageTime(p.stamp_s, p.log_time_s);
        arc = 0.5 * dt * (p.linear_velocity.x() + m.linear_velocity.x());
        turn = 0.5 * dt * (p.angular_velocity.z() + m.angular_velocity.z());
      }
      left += (arc - turn * half_b) / r;
      right += (arc + turn * half_b) / r;
    }
    out.samples.push_back(EncoderSample{t, left, right, static_cast<int>(m.record)});
  }
  return out;
}

}  // namespace calib
