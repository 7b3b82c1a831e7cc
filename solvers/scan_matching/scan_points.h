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
  // Per beam: the polar angle of its point; without a return, its nominal angle (de-skewed: turned
  // by the sensor's rotation at its time).
  std::vector<double> beam_angle_rad;
  // Per beam: (cos, sin) of beam_angle_rad, so that searches need no trigonometry. May be left
  // empty by hand-made ScanPoints (FindCorrespondences then computes it).
  std::vector<Eigen::Vector2d> beam_unit;
  double angle_min_rad = 0.0;
  double angle_increment_rad = 0.0;
  bool full_circle = false;  // The beams close a whole turn (search windows wrap around).
  bool deskewed = false;     // The points were moved to the stamp's frame (a sweep was given).

  int NumBeams() const { return static_cast<int>(point_of_beam.size()); }
  int NumPoints() const { return static_cast<int>(points_m.size()); }
  // The beam whose angle (beam_angle_rad: de-skewed, when the scan was) is nearest to the polar
  // angle phi_rad, for either sign of the increment and any span (a partial scan's beyond its
  // ends: the end beam); −1 without beams.
  int NearestBeam(double phi_rad) const;

 private:
  // The beam phi_rad is found at by stepping from beam from_beam, which looks along
  // from_angle_rad, by the angle between them in beam increments.
  int BeamToward(double phi_rad, int from_beam, double from_angle_rad) const;
};

// The sensor's motion during a sweep as a piecewise-constant body velocity (vx, vy, ω per second,
// in its own frame): velocity[k] from start_s[k] after the stamp on (start_s[0] = 0, increasing;
// velocity[0] also before the stamp). A constant velocity is one piece; a robot that speeds up or
// turns harder within the sweep needs several (e.g. one per encoder sample), because a single
// average velocity bends the de-skewed scan by α·T²/8 (5 mrad at 4 rad/s² over 0.1 s).
struct SweepMotion {
  std::vector<double> start_s{0.0};
  std::vector<Twist2d> velocity{Twist2d::Zero()};

  static SweepMotion Constant(const Twist2d& sensor_velocity) { return {{0.0}, {sensor_velocity}}; }
  // stamp_T_sensor at dt_s after the stamp, for a run of times (any order; fastest ascending).
  std::vector<Pose2d> StampTSensor(const std::vector<double>& dt_s) const;
};

struct ScanPointsOptions {
  // When set, each beam's point is moved to the sensor frame at stamp_s (de-skewing): the beam
  // measured at t = stamp_s + i·time_increment_s sees from stamp_T_sensor(t − stamp_s).
  std::optional<SweepMotion> sweep;
};

// Fails on a malformed scan (non-finite or zero angle increment, non-finite de-skew inputs); a
// well-formed scan with few or no returns gives few or no points.
StatusOr<ScanPoints> MakeScanPoints(const LaserScan& scan, const ScanPointsOptions& options = {});

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_MATCHING_SCAN_POINTS_H_
