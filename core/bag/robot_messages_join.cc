#include <calib/core/bag/robot_messages_join.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <utility>

namespace calib {
namespace {

// A recording that starts later than this after the previous one ends does not continue it.
constexpr double kContinuousGapS = 1.0;
// Gap put between a recording and the next when their clocks overlap.
constexpr double kJoinGapS = 10.0;

double FirstScan(const RobotMessages& m) {
  double t = std::numeric_limits<double>::infinity();
  for (const auto& [topic, scans] : m.scans) {
    if (!scans.empty()) t = std::min(t, scans.front().stamp_s);
  }
  return t;
}

double LastScan(const RobotMessages& m) {
  double t = -std::numeric_limits<double>::infinity();
  for (const auto& [topic, scans] : m.scans) {
    if (!scans.empty()) t = std::max(t, scans.back().stamp_s);
  }
  return t;
}

int64_t RecordsOf(const RobotMessages& m) {
  int64_t n = 0;
  const auto last = [&n](const auto& list) {
    for (const auto& message : list) n = std::max(n, message.record + 1);
  };
  for (const auto& [topic, list] : m.scans) last(list);
  for (const auto& [topic, list] : m.joint_states) last(list);
  for (const auto& [topic, list] : m.odometry) last(list);
  for (const auto& [topic, raw] : m.raw) last(raw.messages);
  last(m.tf);
  last(m.tf_static);
  return n;
}

// The same scans under the same stamps (one recording given twice, perhaps in two formats).
bool SameScans(const RobotMessages& a, const RobotMessages& b) {
  if (a.scans.size() != b.scans.size()) return false;
  for (auto i = a.scans.begin(), j = b.scans.begin(); i != a.scans.end(); ++i, ++j) {
    const std::vector<LaserScan>& x = i->second;
    const std::vector<LaserScan>& y = j->second;
    if (x.size() != y.size() || x.empty()) return false;
    for (const size_t k : {size_t{0}, x.size() / 2, x.size() - 1}) {
      if (x[k].stamp_s != y[k].stamp_s || x[k].ranges_m.size() != y[k].ranges_m.size() ||
          !std::equal(x[k].ranges_m.begin(), x[k].ranges_m.end(), y[k].ranges_m.begin(),
                      [](float p, float q) { return p == q || (p != p && q != q); })) {
        return false;
      }
    }
  }
  return true;
}

// Per joint topic and name, the position step from `before`'s last message to `after`'s first,
// and the largest step between `before`'s last 100 messages.
struct JointJump {
  std::map<std::pair<std::string, std::string>, double> offset;
  bool continuous = true;
};

JointJump JointJumps(const RobotMessages& before, const RobotMessages& after) {
  JointJump out;
  for (const auto& [topic, messages] : after.joint_states) {
    const auto prior = before.joint_states.find(topic);
    if (prior == before.joint_states.end() || prior->second.empty() || messages.empty()) continue;
    const std::vector<JointState>& p = prior->second;
    const JointState& last = p.back();
    const JointState& first = messages.front();
    for (size_t i = 0; i < first.name.size() && i < first.position.size(); ++i) {
      const auto at = std::find(last.name.begin(), last.name.end(), first.name[i]);
      const size_t j = static_cast<size_t>(at - last.name.begin());
      if (at == last.name.end() || j >= last.position.size()) continue;
      double step = 0.0;  // Of the previous recording's last messages.
      for (size_t k = p.size() > 100 ? p.size() - 100 : 1; k < p.size(); ++k) {
        if (j < p[k].position.size() && j < p[k - 1].position.size()) {
          step = std::max(step, std::abs(p[k].position[j] - p[k - 1].position[j]));
        }
      }
      const double jump = first.position[i] - last.position[j];
      out.continuous = out.continuous && std::abs(jump) <= 2.0 * step + 1e-9;
      out.offset[{topic, first.name[i]}] = -jump;
    }
  }
  return out;
}

void Shift(double dt_s, int64_t records, const JointJump* jumps, RobotMessages* m) {
  const auto shift = [&](auto& message) {
    message.stamp_s += dt_s;
    message.log_time_s += dt_s;
    message.record += records;
  };
  for (auto& [topic, list] : m->scans) std::for_each(list.begin(), list.end(), shift);
  for (auto& [topic, list] : m->odometry) std::for_each(list.begin(), list.end(), shift);
  std::for_each(m->tf.begin(), m->tf.end(), shift);
  std::for_each(m->tf_static.begin(), m->tf_static.end(), shift);
  for (auto& [topic, raw] : m->raw) {
    for (RawMessage& r : raw.messages) r.log_time_s += dt_s, r.record += records;
  }
  for (auto& [topic, list] : m->joint_states) {
    for (JointState& j : list) {
      shift(j);
      if (jumps == nullptr) continue;
      for (size_t i = 0; i < j.name.size() && i < j.position.size(); ++i) {
        const auto it = jumps->offset.find({topic, j.name[i]});
        if (it != jumps->offset.end()) j.position[i] += it->second;
      }
    }
  }
}

template <typename T>
void Append(std::map<std::string, std::vector<T>>&& from,
            std::map<std::string, std::vector<T>>* to) {
  for (auto& [topic, messages] : from) {
    std::vector<T>& into = (*to)[topic];
    into.insert(into.end(), std::make_move_iterator(messages.begin()),
                std::make_move_iterator(messages.end()));
  }
}

Status MergeTopics(const RobotMessages& part, RobotMessages* out) {
  for (const TopicInfo& t : part.topics) {
    const auto it = std::find_if(out->topics.begin(), out->topics.end(),
                                 [&](const TopicInfo& o) { return o.name == t.name; });
    if (it == out->topics.end()) {
      out->topics.push_back(t);
    } else if (it->type != t.type) {
      return Status::InvalidInput(part.source + ": topic " + t.name + " is " + t.type + ", but " +
                                  it->type + " in " + out->source +
                                  ": are they one robot's recordings?");
    } else {
      it->message_count += t.message_count;
    }
  }
  return Status::Ok();
}

}  // namespace

StatusOr<RobotMessages> JoinRecordings(std::vector<RobotMessages> parts,
                                       const std::string& source) {
  if (parts.empty()) return Status::InvalidInput(source + ": no recordings to join");
  for (const RobotMessages& p : parts) {
    if (!std::isfinite(FirstScan(p))) return Status::InvalidInput(p.source + ": holds no scans");
  }
  std::stable_sort(parts.begin(), parts.end(), [](const RobotMessages& a, const RobotMessages& b) {
    return FirstScan(a) < FirstScan(b);
  });
  for (size_t k = 1; k < parts.size(); ++k) {
    if (SameScans(parts[k - 1], parts[k])) {
      return Status::InvalidInput(parts[k - 1].source + " and " + parts[k].source +
                                  " hold the same scans: one recording given twice?");
    }
  }
  RobotMessages out = std::move(parts.front());
  for (size_t k = 1; k < parts.size(); ++k) {
    RobotMessages& part = parts[k];
    CALIB_RETURN_IF_ERROR(MergeTopics(part, &out));
    const double end_s = LastScan(out), start_s = FirstScan(part);
    const JointJump jumps = JointJumps(out, part);
    const bool continues =
        start_s > end_s && start_s - end_s <= kContinuousGapS && jumps.continuous;
    const double dt_s = continues || start_s > end_s ? 0.0 : end_s + kJoinGapS - start_s;
    Shift(dt_s, RecordsOf(out), continues ? nullptr : &jumps, &part);
    if (!continues) out.restarts_s.push_back(start_s + dt_s);
    Append(std::move(part.scans), &out.scans);
    Append(std::move(part.joint_states), &out.joint_states);
    Append(std::move(part.odometry), &out.odometry);
    out.tf.insert(out.tf.end(), part.tf.begin(), part.tf.end());
    out.tf_static.insert(out.tf_static.end(), part.tf_static.begin(), part.tf_static.end());
    for (auto& [topic, raw] : part.raw) {
      RawTopic& into = out.raw[topic];
      if (into.type.empty()) into = RawTopic{raw.type, raw.definition, raw.cdr, {}};
      into.messages.insert(into.messages.end(), std::make_move_iterator(raw.messages.begin()),
                           std::make_move_iterator(raw.messages.end()));
    }
    for (const auto& [topic, counts] : part.joint_counts_per_turn) {
      out.joint_counts_per_turn.emplace(topic, counts);
    }
    if (out.counts_per_turn_source.empty())
      out.counts_per_turn_source = part.counts_per_turn_source;
  }
  out.source = source;
  return out;
}

}  // namespace calib
