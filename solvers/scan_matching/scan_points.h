#ifndef CALIB_SOLVERS_SCAN_MATCHING_SCAN_POINTS_H_
#define CALIB_SOLVERS_SCAN_MATCHING_SCAN_POINTS_H_

#include <calib/core/scan/laser_scan.h>
#include <calib/core/se2.h>
#include <calib/core/status.h>

#include <Eigen/Core>
#include <optional>
#include <vector>

// A LaserScan's returns as Cartesian points in the sensor frame at the scan's stamp, kept in beam
// order so that the matcher can search them through their polar angle (as CSM does).
namespace calib {

struct ScanPoints {
  std::vector<Eigen::Vector2d> points_m;    // One per return, in beam order.
  std::vector<Eigen::Vector2d> directions;  // Unit beam direction of each return (range noise).
  std::vector<int> beams;                   // The beam index of each return.
  // Per beam: the index of its return in points_m, or −1 when the beam has no return.
  std::vector<int> point_of_beam;
  // Per beam: the polar angle of its point (its nominal angle when it has no return).
  std::vector<double> beam_angle_rad;
  // Per beam: (cos, sin) of beam_angle_rad, so that searches need no trigonometry. May be left
  // empty by hand-made ScanPoints (FindCorrespondences then computes it).
  std::vector<Eigen::Vector2d> beam_unit;
  double angle_min_rad = 0.0;
  double angle_increment_rad = 0.0;
  bool full_circle = false;  // The beams close a whole turn (search windows wrap around).

  int NumBeams() const { return static_cast<int>(point_of_beam.size()); }
  int NumPoints() const { return static_cast<int>(points_m.size()); }
};

struct ScanPointsOptions {
  // The sensor's constant body velocity (vx, vy, ω) in its own frame during the sweep, per second.
  // When set, each beam's point is moved to the sensor frame at stamp_s (de-skewing): the beam
  // measured at t = stamp_s + i·time_increment_s sees from stamp_T_t = Exp(ξ·(t − stamp_s)).
  std::optional<Twist2d> sensor_velocity;
};

// Fails on a malformed scan (non-finite or zero angle increment, non-finite de-skew inputs); a
// well-formed scan with few or no returns gives few or no points.
StatusOr<ScanPoints> MakeScanPoints(const LaserScan& scan, const ScanPointsOptions& options = {});

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_MATCHING_SCAN_POINTS_H_
