#ifndef CALIB_CORE_SE2_H_
#define CALIB_CORE_SE2_H_

#include <Eigen/Core>
#include <cmath>

// Planar rigid motions as (x, y, theta), templated on the scalar so that the same code serves
// double and ceres::Jet. Frame names follow `a_T_b`: the pose of frame b expressed in frame a.
namespace calib {

template <typename T>
using Pose2 = Eigen::Matrix<T, 3, 1>;
using Pose2d = Pose2<double>;

// Wraps an angle to (-pi, pi] by adding whole turns, which keeps the derivative equal to one for
// Jets and costs no trigonometry; far-off or non-finite angles go through atan2.
template <typename T>
T WrapAngle(T angle) {
  using std::abs;
  using std::atan2;
  using std::cos;
  using std::sin;
  if (!(abs(angle) < T(64.0))) {
    angle = atan2(sin(angle), cos(angle));
    if (angle <= T(-M_PI)) angle += T(2.0 * M_PI);
    return angle;
  }
  while (angle > T(M_PI)) angle -= T(2.0 * M_PI);
  while (angle <= T(-M_PI)) angle += T(2.0 * M_PI);
  return angle;
}

// a ⊕ b: the pose b (given in frame a) expressed in a's parent frame.
template <typename T>
Pose2<T> Compose(const Pose2<T>& a, const Pose2<T>& b) {
  using std::cos;
  using std::sin;
  const T c = cos(a(2));
  const T s = sin(a(2));
  return Pose2<T>(a(0) + c * b(0) - s * b(1), a(1) + s * b(0) + c * b(1), a(2) + b(2));
}

// a⁻¹, so that a ⊕ a⁻¹ = 0.
template <typename T>
Pose2<T> Inverse(const Pose2<T>& a) {
  using std::cos;
  using std::sin;
  const T c = cos(a(2));
  const T s = sin(a(2));
  return Pose2<T>(-c * a(0) - s * a(1), s * a(0) - c * a(1), -a(2));
}

// a⁻¹ ∘ c: the displacement from pose a to pose c expressed in frame a (the papers' c ⊖ a).
template <typename T>
Pose2<T> Between(const Pose2<T>& a, const Pose2<T>& c) {
  using std::cos;
  using std::sin;
  const T ca = cos(a(2));
  const T sa = sin(a(2));
  const T dx = c(0) - a(0);
  const T dy = c(1) - a(1);
  return Pose2<T>(ca * dx + sa * dy, -sa * dx + ca * dy, c(2) - a(2));
}

// The sensor displacement for a robot displacement o and the sensor mounting base_T_sensor:
// s = ℓ⁻¹ ∘ o ∘ ℓ.
template <typename T>
Pose2<T> SensorMotionFromRobotMotion(const Pose2<T>& base_T_sensor, const Pose2<T>& robot_motion) {
  return Between(base_T_sensor, Compose(robot_motion, base_T_sensor));
}

}  // namespace calib

#endif  // CALIB_CORE_SE2_H_
