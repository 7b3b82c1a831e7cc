#include <calib/solvers/scan_matching/scan_points.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

namespace calib {
namespace {

bool IsValid(const SweepMotion& sweep) {
  if (sweep.start_s.empty() || sweep.start_s.size() != sweep.velocity.size() ||
      sweep.start_s[0] != 0.0) {
    return false;
  }
  for (size_t k = 0; k < sweep.start_s.size(); ++k) {
    if (!sweep.velocity[k].allFinite() || !std::isfinite(sweep.start_s[k])) return false;
    if (k > 0 && !(sweep.start_s[k] > sweep.start_s[k - 1])) return false;
  }
  return true;
}

Status CheckScan(const LaserScan& scan, const ScanPointsOptions& options) {
  const std::string where = "scan (record " + std::to_string(scan.record) + "): ";
  if (!std::isfinite(scan.angle_min_rad) || !std::isfinite(scan.angle_increment_rad)) {
    return Status::InvalidInput(where + "angle_min or angle_increment is not finite");
  }
  if (scan.ranges_m.size() > 1 && scan.angle_increment_rad == 0.0) {
    return Status::InvalidInput(where + "angle_increment is zero with more than one beam");
  }
  if (std::abs(scan.angle_increment_rad) * (static_cast<double>(scan.ranges_m.size()) - 1) >
      2.0 * M_PI + 1e-6) {
    return Status::InvalidInput(where + "the beams span more than a whole turn");
  }
  if (options.sweep.has_value()) {
    if (!IsValid(*options.sweep)) {
      return Status::InvalidInput(where +
                                  "the de-skewing motion is not finite or its pieces are not in "
                                  "time order from 0");
    }
    if (!std::isfinite(scan.time_increment_s)) {
      return Status::InvalidInput(where + "time_increment is not finite");
    }
  }
  return Status::Ok();
}

}  // namespace

int ScanPoints::BeamToward(double phi_rad, int from_beam, double from_angle_rad) const {
  const int n = NumBeams();
  // The offset wrapped into (−π, π]: on a scan spanning more than half a turn it may land a whole
  // turn away from the beams; then the nearer of the two ways to them.
  const double offset = WrapAngle(phi_rad - from_angle_rad) / angle_increment_rad;
  // Rounded half away from zero, as std::round, without its library call (a search per point).
  double beam =
      from_beam + static_cast<double>(static_cast<int64_t>(offset + (offset < 0.0 ? -0.5 : 0.5)));
  if (full_circle) return ((static_cast<int>(beam) % n) + n) % n;
  const double turn = 2.0 * M_PI / std::abs(angle_increment_rad);
  if (beam < 0 && beam + turn - (n - 1) < -beam) beam += turn;
  if (beam > n - 1 && -(beam - turn) < beam - (n - 1)) beam -= turn;
  return static_cast<int>(std::clamp(beam, 0.0, static_cast<double>(n - 1)));
}

int ScanPoints::NearestBeam(double phi_rad) const {
  const int n = NumBeams();
  if (n == 0) return -1;
  if (angle_increment_rad == 0.0) return 0;
  int k = BeamToward(phi_rad, 0, angle_min_rad);
  if (!deskewed || static_cast<int>(beam_angle_rad.size()) != n) return k;
  // De-skewed, beam k looks along its nominal angle turned by the sensor's rotation at its time:
  // tens of beams away in a fast turn (0.5 rad over a 0.1 s sweep at 5 rad/s). Step towards phi
  // by the angle still missing; each step leaves the share ω·time_increment/angle_increment of it.
  int previous = -1;
  for (int iteration = 0; iteration < 8; ++iteration) {
    const int next = BeamToward(phi_rad, k, beam_angle_rad[k]);
    if (next == k) break;
    if (next == previous) {  // Back and forth across a gap (a sweep turning against its beams).
      const auto off = [&](int b) { return std::abs(WrapAngle(phi_rad - beam_angle_rad[b])); };
      return off(next) < off(k) ? next : k;
    }
    previous = k;
    k = next;
  }
  return k;
}

std::vector<Pose2d> SweepMotion::StampTSensor(const std::vector<double>& dt_s) const {
  std::vector<Pose2d> knots{Pose2d::Zero()};  // stamp_T_sensor at start_s[k].
  for (size_t k = 1; k < start_s.size(); ++k) {
    knots.push_back(
        Compose(knots.back(), Exp<double>(velocity[k - 1] * (start_s[k] - start_s[k - 1]))));
  }
  std::vector<Pose2d> out;
  out.reserve(dt_s.size());
  size_t k = 0;
  for (const double t : dt_s) {
    if (k >= start_s.size() || t < start_s[k]) k = 0;  // Out of order: search again.
    while (k + 1 < start_s.size() && t >= start_s[k + 1]) ++k;
    out.push_back(Compose(knots[k], Exp<double>(velocity[k] * (t - start_s[k]))));
  }
  return out;
}

StatusOr<ScanPoints> MakeScanPoints(const LaserScan& scan, const ScanPointsOptions& options) {
  CALIB_RETURN_IF_ERROR(CheckScan(scan, options));
  const int num_beams = static_cast<int>(scan.ranges_m.size());
  ScanPoints out;
  out.angle_min_rad = scan.angle_min_rad;
  out.angle_increment_rad = scan.angle_increment_rad;
  const double span_rad = std::abs(scan.angle_increment_rad) * num_beams;
  out.full_circle =
      num_beams > 2 && span_rad >= 2.0 * M_PI - 0.5 * std::abs(scan.angle_increment_rad);
  out.point_of_beam.assign(num_beams, -1);
  out.beam_angle_rad.resize(num_beams);
  out.beam_unit.resize(num_beams);
  out.points_m.reserve(num_beams);
  out.directions.reserve(num_beams);
  out.beams.reserve(num_beams);
  std::vector<Pose2d> stamp_T_beam;
  out.deskewed = options.sweep.has_value();
  if (options.sweep.has_value()) {
    std::vector<double> dt_s(num_beams);
    for (int i = 0; i < num_beams; ++i) dt_s[i] = i * scan.time_increment_s;
    stamp_T_beam = options.sweep->StampTSensor(dt_s);
  }
  for (int i = 0; i < num_beams; ++i) {
    const double angle_rad = scan.BeamAngle(i);
    Eigen::Vector2d direction(std::cos(angle_rad), std::sin(angle_rad));
    out.beam_angle_rad[i] = angle_rad;
    out.beam_unit[i] = direction;
    if (!scan.IsReturn(i)) {
      // Turned with the sensor, so that the angles stay in beam order for the searches.
      if (options.sweep.has_value()) {
        out.beam_angle_rad[i] += stamp_T_beam[i](2);
        out.beam_unit[i] = {std::cos(out.beam_angle_rad[i]), std::sin(out.beam_angle_rad[i])};
      }
      continue;
    }
    const double range_m = scan.ranges_m[i];
    Eigen::Vector2d point_m = range_m * direction;
    if (options.sweep.has_value()) {
      // The point seen from the stamp's frame is stamp_T_beam ⊕ point.
      const Pose2d& motion = stamp_T_beam[i];
      const Eigen::Vector2d p = point_m;
      point_m = Compose(motion, Pose2d(p.x(), p.y(), 0.0)).head<2>();
      const double c = std::cos(motion(2));
      const double s = std::sin(motion(2));
      direction = Eigen::Vector2d(c * direction.x() - s * direction.y(),
                                  s * direction.x() + c * direction.y());
      out.beam_angle_rad[i] =
          angle_rad + WrapAngle(std::atan2(point_m.y(), point_m.x()) - angle_rad);
      out.beam_unit[i] =
          Eigen::Vector2d(std::cos(out.beam_angle_rad[i]), std::sin(out.beam_angle_rad[i]));
    }
    out.point_of_beam[i] = static_cast<int>(out.points_m.size());
    out.points_m.push_back(point_m);
    out.directions.push_back(direction);
    out.beams.push_back(i);
  }
  return out;
}

}  // namespace calib
