#ifndef CALIB_CORE_SE2_H_
#define CALIB_CORE_SE2_H_

#include <calib/core/sin_cos.h>

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

// ---------------------------------------------------------------------------------------------
// The exponential map of SE(2) (Sophus/manif style, on plain (x, y, θ) vectors). A twist
// ξ = (ρx, ρy, θ) is a constant body velocity held for unit time; Exp(ξ) is the pose it reaches,
// the constant-velocity arc:
//   Exp(ξ) = (V(θ)·ρ, θ),  V(θ) = [[S, −C], [C, S]],  S = sin θ/θ,  C = (1 − cos θ)/θ.
// Near θ = 0, S, C and their derivatives come from their Taylor series (one cut-off for all).
// At the cut-off the first term each series leaves out is at most 2e-16 (θ⁶/5040 in S, about
// one rounding of 1; the committed simulated logs depend on these exact values), and a Jet's
// derivative through the S series misses θ⁵/840 ≈ 1e-13; the closed forms round 1 − cos θ to
// ~1e-12 relative there. Values and derivatives are thus continuous across the cut-off.
template <typename T>
using Twist2 = Eigen::Matrix<T, 3, 1>;  // (ρx, ρy, θ).
using Twist2d = Twist2<double>;

// Below this |θ| the series replace the closed forms.
inline constexpr double kSe2SmallAngle = 1e-2;

// S = sin θ/θ and C = (1 − cos θ)/θ, from sin θ and cos θ when the caller has them (they are
// not read below the series' cut-off).
template <typename T>
void ArcCoefficients(const T& angle, const T& sin_angle, const T& cos_angle, T* sin_over_angle,
                     T* one_minus_cos_over_angle) {
  using std::abs;
  if (abs(angle) < T(kSe2SmallAngle)) {
    // S = 1 − θ²/6 + θ⁴/120, C = θ/2·(1 − θ²/12 + θ⁴/360).
    const T a2 = angle * angle;
    *sin_over_angle = T(1) - a2 / T(6) + a2 * a2 / T(120);
    *one_minus_cos_over_angle = angle / T(2) * (T(1) - a2 / T(12) + a2 * a2 / T(360));
  } else {
    *sin_over_angle = sin_angle / angle;
    *one_minus_cos_over_angle = (T(1) - cos_angle) / angle;
  }
}

// sin θ and cos θ for the arc functions' callers without them; below kSe2SmallAngle their series
// read neither, so none is computed.
template <typename T>
void ArcSinCos(const T& angle, T* sin_angle, T* cos_angle) {
  using std::abs;
  using std::cos;
  using std::sin;
  const bool small = abs(angle) < T(kSe2SmallAngle);
  *sin_angle = small ? T(0) : sin(angle);
  *cos_angle = small ? T(1) : cos(angle);
}

// For plain numbers, SinCos: the angle is nearly always a turn within one interval.
inline void ArcSinCos(const double& angle, double* sin_angle, double* cos_angle) {
  if (std::abs(angle) < kSe2SmallAngle) {
    *sin_angle = 0.0, *cos_angle = 1.0;
  } else {
    SinCos(angle, sin_angle, cos_angle);
  }
}

template <typename T>
void ArcCoefficients(const T& angle, T* sin_over_angle, T* one_minus_cos_over_angle) {
  T sin_angle, cos_angle;
  ArcSinCos(angle, &sin_angle, &cos_angle);
  ArcCoefficients(angle, sin_angle, cos_angle, sin_over_angle, one_minus_cos_over_angle);
}

// S' = dS/dθ = (θ cos θ − sin θ)/θ² and C' = dC/dθ = (θ sin θ − 1 + cos θ)/θ², from sin θ and
// cos θ when the caller has them.
template <typename T>
void ArcCoefficientDerivatives(const T& angle, const T& sin_angle, const T& cos_angle,
                               T* d_sin_over_angle, T* d_one_minus_cos_over_angle) {
  using std::abs;
  if (abs(angle) < T(kSe2SmallAngle)) {
    // S' = −θ/3·(1 − θ²/10 + θ⁴/280), C' = 1/2 − θ²/8 + θ⁴/144 − θ⁶/5760.
    const T a2 = angle * angle;
    *d_sin_over_angle = -angle / T(3) * (T(1) - a2 / T(10) + a2 * a2 / T(280));
    *d_one_minus_cos_over_angle = T(0.5) - a2 / T(8) + a2 * a2 / T(144) - a2 * a2 * a2 / T(5760);
  } else {
    *d_sin_over_angle = (angle * cos_angle - sin_angle) / (angle * angle);
    *d_one_minus_cos_over_angle = (angle * sin_angle - T(1) + cos_angle) / (angle * angle);
  }
}

template <typename T>
void ArcCoefficientDerivatives(const T& angle, T* d_sin_over_angle, T* d_one_minus_cos_over_angle) {
  T sin_angle, cos_angle;
  ArcSinCos(angle, &sin_angle, &cos_angle);
  ArcCoefficientDerivatives(angle, sin_angle, cos_angle, d_sin_over_angle,
                            d_one_minus_cos_over_angle);
}

// Exp(ξ) = (S·ρx − C·ρy, C·ρx + S·ρy, θ).
template <typename T>
Pose2<T> Exp(const Twist2<T>& twist) {
  T s, c;
  ArcCoefficients(twist(2), &s, &c);
  return Pose2<T>(s * twist(0) - c * twist(1), c * twist(0) + s * twist(1), twist(2));
}

// ∂Exp(ξ)/∂ξ = [[S, −C, S'ρx − C'ρy], [C, S, C'ρx + S'ρy], [0, 0, 1]].
template <typename T>
Eigen::Matrix<T, 3, 3> ExpJacobian(const Twist2<T>& twist) {
  T s, c, ds, dc;
  ArcCoefficients(twist(2), &s, &c);
  ArcCoefficientDerivatives(twist(2), &ds, &dc);
  Eigen::Matrix<T, 3, 3> j;
  j << s, -c, ds * twist(0) - dc * twist(1), c, s, dc * twist(0) + ds * twist(1), T(0), T(0), T(1);
  return j;
}

// Log(p) = (V(θ)⁻¹·(x, y), θ) with V⁻¹ = [[S, C], [−C, S]]/(S² + C²), the inverse of Exp for
// |θ| < 2π (θ is taken as stored, not wrapped).
template <typename T>
Twist2<T> Log(const Pose2<T>& pose) {
  T s, c;
  ArcCoefficients(pose(2), &s, &c);
  const T norm = s * s + c * c;  // = 2(1 − cos θ)/θ², positive for |θ| < 2π.
  return Twist2<T>((s * pose(0) + c * pose(1)) / norm, (s * pose(1) - c * pose(0)) / norm, pose(2));
}

// ∂Log(p)/∂p = (∂Exp/∂ξ)⁻¹ at ξ = Log(p): [[V⁻¹, −V⁻¹·V'·ρ], [0, 0, 1]].
template <typename T>
Eigen::Matrix<T, 3, 3> LogJacobian(const Pose2<T>& pose) {
  const Eigen::Matrix<T, 3, 3> d_exp = ExpJacobian(Log(pose));
  // V = [[S, −C], [C, S]], so V⁻¹ = [[S, C], [−C, S]]/(S² + C²).
  const T s = d_exp(0, 0);
  const T c = d_exp(1, 0);
  const T norm = s * s + c * c;
  Eigen::Matrix<T, 2, 2> v_inverse;
  v_inverse << s / norm, c / norm, -c / norm, s / norm;
  Eigen::Matrix<T, 3, 3> j = Eigen::Matrix<T, 3, 3>::Identity();
  j.template topLeftCorner<2, 2>() = v_inverse;
  j.template topRightCorner<2, 1>() = -(v_inverse * d_exp.template topRightCorner<2, 1>());
  return j;
}

}  // namespace calib

#endif  // CALIB_CORE_SE2_H_
