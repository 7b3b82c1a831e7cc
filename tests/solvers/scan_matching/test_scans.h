#ifndef CALIB_TESTS_SOLVERS_SCAN_MATCHING_TEST_SCANS_H_
#define CALIB_TESTS_SOLVERS_SCAN_MATCHING_TEST_SCANS_H_

#include <calib/core/scan/laser_scan.h>
#include <calib/core/se2.h>
#include <calib/solvers/scan_matching/scan_points.h>

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <vector>

// A minimal test-only ray caster over line segments (to be replaced by core/scan's simulator).
namespace calib::test_scans {

struct Wall {
  Eigen::Vector2d a, b;
};

inline void AddBox(double x0, double y0, double x1, double y1, std::vector<Wall>* walls) {
  walls->push_back({{x0, y0}, {x1, y0}});
  walls->push_back({{x1, y0}, {x1, y1}});
  walls->push_back({{x1, y1}, {x0, y1}});
  walls->push_back({{x0, y1}, {x0, y0}});
}

// A 10 m × 6 m room centred on the origin with three boxes and a slanted wall piece.
inline std::vector<Wall> RoomWithBoxes() {
  std::vector<Wall> walls;
  AddBox(-5.0, -3.0, 5.0, 3.0, &walls);
  AddBox(2.0, 1.0, 2.8, 1.6, &walls);
  AddBox(-3.5, -2.2, -2.7, -1.2, &walls);
  AddBox(0.5, -2.4, 1.1, -1.9, &walls);
  walls.push_back({{-4.0, 2.0}, {-2.5, 2.9}});
  return walls;
}

// Two parallel walls 2 m apart, far longer than the sensor's range.
inline std::vector<Wall> Corridor() {
  return {{{-1000.0, -1.0}, {1000.0, -1.0}}, {{-1000.0, 1.0}, {1000.0, 1.0}}};
}

// The distance along the ray (origin o, unit direction d) to the nearest wall, or +inf.
inline double CastRay(const std::vector<Wall>& walls, const Eigen::Vector2d& o,
                      const Eigen::Vector2d& d) {
  double best = std::numeric_limits<double>::infinity();
  for (const Wall& w : walls) {
    const Eigen::Vector2d e = w.b - w.a;
    const double denom = d.x() * e.y() - d.y() * e.x();
    if (std::abs(denom) < 1e-15) continue;
    const Eigen::Vector2d ao = w.a - o;
    const double t = (ao.x() * e.y() - ao.y() * e.x()) / denom;
    const double u = (ao.x() * d.y() - ao.y() * d.x()) / denom;
    if (t > 0.0 && u >= 0.0 && u <= 1.0) best = std::min(best, t);
  }
  return best;
}

struct ScanSpec {
  int beams = 360;
  double fov_rad = 2.0 * M_PI;  // A whole turn when 2π (no repeated beam).
  double range_max_m = 20.0;
  double range_sigma_m = 0.0;
  double sweep_time_s = 0.0;           // time_increment = sweep_time / beams.
  Twist2d velocity = Twist2d::Zero();  // Body velocity of the sensor during the sweep.
  std::optional<SweepMotion> motion;   // When set, used instead of `velocity`.
};

// The scan seen from world_T_sensor (the pose at the first beam); each later beam from
// world_T_sensor ⊕ Exp(ξ·t) when the sensor moves during the sweep.
inline LaserScan CastScan(const std::vector<Wall>& walls, const Pose2d& world_T_sensor,
                          const ScanSpec& spec, std::mt19937* rng = nullptr) {
  LaserScan scan;
  const bool full = spec.fov_rad >= 2.0 * M_PI - 1e-12;
  scan.angle_increment_rad = full ? spec.fov_rad / spec.beams : spec.fov_rad / (spec.beams - 1);
  scan.angle_min_rad = -0.5 * spec.fov_rad;
  scan.time_increment_s = spec.sweep_time_s / spec.beams;
  scan.range_min_m = 0.05;
  scan.range_max_m = spec.range_max_m;
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<double> beam_dt_s(spec.beams);
  for (int i = 0; i < spec.beams; ++i) beam_dt_s[i] = i * scan.time_increment_s;
  const std::vector<Pose2d> stamp_T_beam =
      spec.motion.value_or(SweepMotion::Constant(spec.velocity)).StampTSensor(beam_dt_s);
  for (int i = 0; i < spec.beams; ++i) {
    const Pose2d pose = Compose(world_T_sensor, stamp_T_beam[i]);
    const double angle = pose(2) + scan.BeamAngle(i);
    double range =
        CastRay(walls, pose.head<2>(), Eigen::Vector2d(std::cos(angle), std::sin(angle)));
    if (range > spec.range_max_m) range = std::numeric_limits<double>::infinity();
    if (rng != nullptr && spec.range_sigma_m > 0.0 && std::isfinite(range)) {
      range += spec.range_sigma_m * noise(*rng);
    }
    scan.ranges_m.push_back(static_cast<float>(range));
  }
  return scan;
}

}  // namespace calib::test_scans

#endif  // CALIB_TESTS_SOLVERS_SCAN_MATCHING_TEST_SCANS_H_
