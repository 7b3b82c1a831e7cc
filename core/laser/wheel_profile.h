#ifndef CALIB_CORE_LASER_WHEEL_PROFILE_H_
#define CALIB_CORE_LASER_WHEEL_PROFILE_H_

#include <calib/core/laser/laser_simulator.h>
#include <calib/core/random.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

// The laser simulator's wheel speeds (not part of the API).
//
// Wheel speeds are a piecewise analytic profile: segments of constant commanded targets g, and
// within a segment either constant speeds (speed_time_constant_s == 0; segments then start only
// at interval boundaries) or a first-order lag φ(t) = g + (φ_a − g)·exp(−(t − a)/τ). The
// cumulative encoder angles Φ(t) are therefore known in closed form at any time.
namespace calib {
namespace laser_sim_internal {

// One commanded target, held from start_s until the next segment starts; the first segment also
// covers all earlier times (at constant speed, since the profile starts at its target).
struct SpeedSegment {
  double start_s = 0.0;
  Eigen::Array2d target = Eigen::Array2d::Zero();  // (left, right), rad/s.
  Eigen::Array2d speed = Eigen::Array2d::Zero();   // Actual speeds at start_s.
  Eigen::Array2d angle = Eigen::Array2d::Zero();   // Cumulative wheel angles at start_s.
};

class WheelProfile {
 public:
  WheelProfile(double time_constant_s, std::vector<SpeedSegment> segments)
      : tau_(time_constant_s), segments_(std::move(segments)) {}

  bool smooth() const { return tau_ > 0.0; }
  double tau() const { return tau_; }
  const std::vector<SpeedSegment>& segments() const { return segments_; }

  // The segment holding t; `cursor` remembers the last answer, since queries mostly move forward.
  size_t Find(double t, size_t* cursor) const {
    size_t i = std::min(*cursor, segments_.size() - 1);
    while (i + 1 < segments_.size() && segments_[i + 1].start_s <= t) ++i;
    while (i > 0 && segments_[i].start_s > t) --i;
    return *cursor = i;
  }

  // Φ(a + dt) − Φ(a) = g·dt + (φ_a − g)·τ·(1 − exp(−dt/τ)). Only the first segment is evaluated
  // at dt < 0, where φ_a = g; the clamp keeps 0·exp(large) from becoming 0·inf.
  Eigen::Array2d Rotation(const SpeedSegment& segment, double dt) const {
    if (!smooth()) return segment.target * dt;
    return segment.target * dt +
           (segment.speed - segment.target) * (-tau_ * std::expm1(-std::max(dt, 0.0) / tau_));
  }
  Eigen::Array2d Speed(const SpeedSegment& segment, double dt) const {
    if (!smooth()) return segment.target;
    return segment.target + (segment.speed - segment.target) * std::exp(-std::max(dt, 0.0) / tau_);
  }

  // Cumulative wheel angles Φ(t).
  Eigen::Array2d Angle(double t, size_t* cursor) const {
    const SpeedSegment& segment = segments_[Find(t, cursor)];
    return segment.angle + Rotation(segment, t - segment.start_s);
  }

 private:
  double tau_;
  std::vector<SpeedSegment> segments_;
};

// Constant speeds: targets change only at interval boundaries, after ~Exponential(segment_mean_s)
// seconds of holding. `targets` is the simulator's stream of commanded targets.
WheelProfile ConstantSpeedProfile(const LaserSimOptions& options,
                                  const std::vector<double>& boundaries, Random* targets);

// Smooth speeds: a new target every ~Exponential(segment_mean_s) seconds, followed through the
// first-order lag. The profile starts at its first target and runs until `end_s`.
WheelProfile SmoothProfile(const LaserSimOptions& options, double end_s, Random* targets);

}  // namespace laser_sim_internal
}  // namespace calib

#endif  // CALIB_CORE_LASER_WHEEL_PROFILE_H_
