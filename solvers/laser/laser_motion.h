#ifndef CALIB_SOLVERS_LASER_LASER_MOTION_H_
#define CALIB_SOLVERS_LASER_LASER_MOTION_H_

#include <calib/core/laser/laser_log.h>

#include <string>
#include <vector>

namespace calib {

// What kinds of motion a log holds, from the wheel rotations alone (no calibration needed).
// An interval turns when |Δφ_r − Δφ_l| is a noticeable part of |Δφ_l| + |Δφ_r|, and translates
// when |Δφ_r + Δφ_l| is.
struct LaserMotionCensus {
  int total = 0;
  int still = 0;          // Wheels (nearly) at rest.
  int pure_rotation = 0;  // Turning on the spot.
  int straight = 0;       // Driving without turning.
  int arc = 0;            // Turning and translating together.
  int turning() const { return pure_rotation + arc; }
  void Add(const LaserMotionCensus& other) {
    total += other.total, still += other.still, pure_rotation += other.pure_rotation;
    straight += other.straight, arc += other.arc;
  }
  int translating() const { return straight + arc; }
};

// Over the intervals `use` marks (all when null), in chunks on up to `num_threads` threads.
LaserMotionCensus CountLaserMotion(const std::vector<LaserInterval>& intervals,
                                   const std::vector<bool>* use = nullptr, int num_threads = 2);

// The minimum motion the laser problem needs, in words, or "" when the log has it. The
// parameters are identifiable only with both turning and translation in the log.
std::string DescribeMissingLaserMotion(const LaserMotionCensus& census);

// Total wheel rotations (Δφ_l, Δφ_r) over an interval, rad.
inline Eigen::Vector2d IntervalWheelRotation(const LaserInterval& interval) {
  if (interval.steps.empty()) {
    return Eigen::Vector2d(interval.left_speed, interval.right_speed) * interval.duration_s;
  }
  Eigen::Vector2d total = Eigen::Vector2d::Zero();
  for (const WheelStep& step : interval.steps)
    total += Eigen::Vector2d(step.left_rad, step.right_rad);
  return total;
}

}  // namespace calib

#endif  // CALIB_SOLVERS_LASER_LASER_MOTION_H_
