#ifndef CALIB_CORE_DIFF_DRIVE_H_
#define CALIB_CORE_DIFF_DRIVE_H_

#include <calib/core/se2.h>

#include <Eigen/Core>
#include <cmath>
#include <vector>

// Differential-drive kinematics (Censi et al. 2008, §II-A). Wheel speeds are positive when the
// wheel drives the robot forward: v = (r_l·φ_l + r_r·φ_r)/2, ω = (r_r·φ_r − r_l·φ_l)/b.
namespace calib {

struct OdometryParams {
  double left_radius_m = 0.0;
  double right_radius_m = 0.0;
  double wheelbase_m = 0.0;
};

// J maps wheel speeds (φ_l, φ_r) to (v, ω): J = [[r_l/2, r_r/2], [−r_l/b, r_r/b]].
template <typename T>
Eigen::Matrix<T, 2, 2> WheelJacobian(const T& left_radius, const T& right_radius,
                                     const T& wheelbase) {
  Eigen::Matrix<T, 2, 2> j;
  j << left_radius / T(2), right_radius / T(2), -left_radius / wheelbase, right_radius / wheelbase;
  return j;
}

// The displacement along an arc of length `distance` that turns by `angle` (eqs. 5–7 with
// distance = v·T, angle = ω·T): Exp(distance, 0, angle) = (d·sin θ/θ, d·(1 − cos θ)/θ, θ).
template <typename T>
Pose2<T> ArcDisplacement(const T& distance, const T& angle) {
  return Exp(Twist2<T>(distance, T(0), angle));
}

// The robot displacement over a step in which the wheels turn by (left_rad, right_rad) at
// constant speed. Time drops out: only the wheel rotations matter.
template <typename T>
Pose2<T> WheelStepDisplacement(const T& left_radius, const T& right_radius, const T& wheelbase,
                               const T& left_rad, const T& right_rad) {
  const T distance = (left_radius * left_rad + right_radius * right_rad) / T(2);
  const T angle = (right_radius * right_rad - left_radius * left_rad) / wheelbase;
  return ArcDisplacement(distance, angle);
}

// Wheel rotation increments over a sub-step of an interval (Censi §II-D: speeds that are not
// constant over an interval are integrated as a sequence of constant-speed steps).
struct WheelStep {
  double duration_s = 0.0;
  double left_rad = 0.0;
  double right_rad = 0.0;
};

// Composes the constant-speed arcs of consecutive steps.
template <typename T>
Pose2<T> IntegrateWheelSteps(const T& left_radius, const T& right_radius, const T& wheelbase,
                             const std::vector<WheelStep>& steps) {
  Pose2<T> motion = Pose2<T>::Zero();
  for (const WheelStep& step : steps) {
    motion = Compose(motion, WheelStepDisplacement(left_radius, right_radius, wheelbase,
                                                   T(step.left_rad), T(step.right_rad)));
  }
  return motion;
}

}  // namespace calib

#endif  // CALIB_CORE_DIFF_DRIVE_H_
