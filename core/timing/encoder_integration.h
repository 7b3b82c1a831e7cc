#ifndef CALIB_CORE_TIMING_ENCODER_INTEGRATION_H_
#define CALIB_CORE_TIMING_ENCODER_INTEGRATION_H_

#include <calib/core/diff_drive.h>
#include <calib/core/encoder_sample.h>
#include <calib/core/se2.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

// Encoder integration (Martinelli 2009, eqs. 1–2 and §8.1): the robot displacement between two
// times from cumulative wheel rotations, with the correction factors δR, δL, δB, and its
// first-order covariance; the bearing odometry terms and the laser latent-time calibration use it.
namespace calib {

// Cumulative wheel rotations at t by linear interpolation (clamped to the samples' span): exact
// where the speeds change only at the polls (the bearing simulator, a dense encoder stream); the
// laser streams, polled more slowly than their scans, use the cubic of wheel_angle_spline.h.
// `odometry` must be sorted by time and non-empty. Time is a double or any scalar ordered
// against doubles (a ceres::Jet: the rotations then carry d/dt, the step's wheel speeds).
template <typename Time>
void InterpolateWheelAngles(const std::vector<EncoderSample>& odometry, const Time& t_s,
                            Time* left_rad, Time* right_rad) {
  if (!(odometry.front().t_s < t_s)) {
    *left_rad = Time(odometry.front().left_rad);
    *right_rad = Time(odometry.front().right_rad);
    return;
  }
  if (!(t_s < odometry.back().t_s)) {
    *left_rad = Time(odometry.back().left_rad);
    *right_rad = Time(odometry.back().right_rad);
    return;
  }
  const auto after =
      std::upper_bound(odometry.begin(), odometry.end(), t_s,
                       [](const Time& t, const EncoderSample& sample) { return t < sample.t_s; });
  const EncoderSample& b = *after;
  const EncoderSample& a = *(after - 1);
  if (t_s == a.t_s) {
    // On a sample the angles have a kink: their derivative (a Jet's d/dt) is the mean of the two
    // steps' speeds, not the later step's alone (the same value, a symmetric sensitivity).
    const EncoderSample& z = *(after - 2);
    const double left_speed = 0.5 * ((b.left_rad - a.left_rad) / (b.t_s - a.t_s) +
                                     (a.left_rad - z.left_rad) / (a.t_s - z.t_s));
    const double right_speed = 0.5 * ((b.right_rad - a.right_rad) / (b.t_s - a.t_s) +
                                      (a.right_rad - z.right_rad) / (a.t_s - z.t_s));
    *left_rad = a.left_rad + (t_s - a.t_s) * left_speed;
    *right_rad = a.right_rad + (t_s - a.t_s) * right_speed;
    return;
  }
  const Time f = (t_s - a.t_s) / (b.t_s - a.t_s);
  *left_rad = a.left_rad + f * (b.left_rad - a.left_rad);
  *right_rad = a.right_rad + f * (b.right_rad - a.right_rad);
}

// The robot displacement over one step in which the wheels turn by (left, right) rad at
// constant speed, for nominal r, B and the correction factors of eq. 2.
template <typename T, typename Angle>
Pose2<T> EncoderStepDisplacement(double wheel_radius_m, double wheelbase_m, const T& delta_r,
                                 const T& delta_l, const T& delta_b, const Angle& left_rad,
                                 const Angle& right_rad) {
  const T right = delta_r * (wheel_radius_m * right_rad);
  const T left = delta_l * (wheel_radius_m * left_rad);
  return ArcDisplacement((right + left) / T(2), (right - left) / (delta_b * T(wheelbase_m)));
}

// The robot displacement from its pose at t0 to its pose at t1, expressed in the frame at t0
// (a⁻¹ ∘ c), integrating the encoder steps between as constant-speed arcs (eqs. 1–2). Times are
// clamped to the samples' span; t1 < t0 gives the inverse displacement. Times are doubles, or of
// the scalar T when the displacement is differentiated with respect to them (a time offset).
template <typename T, typename Time>
Pose2<T> IntegrateEncoders(const std::vector<EncoderSample>& odometry, const Time& t0_s,
                           const Time& t1_s, double wheel_radius_m, double wheelbase_m,
                           const T& delta_r, const T& delta_l, const T& delta_b) {
  if (odometry.empty()) return Pose2<T>::Zero();
  if (t1_s < t0_s) {
    return Inverse(IntegrateEncoders(odometry, t1_s, t0_s, wheel_radius_m, wheelbase_m, delta_r,
                                     delta_l, delta_b));
  }
  Time left, right, left_end, right_end;
  InterpolateWheelAngles(odometry, t0_s, &left, &right);
  InterpolateWheelAngles(odometry, t1_s, &left_end, &right_end);
  Pose2<T> motion = Pose2<T>::Zero();
  auto it =
      std::upper_bound(odometry.begin(), odometry.end(), t0_s,
                       [](const Time& t, const EncoderSample& sample) { return t < sample.t_s; });
  for (; it != odometry.end() && it->t_s < t1_s; ++it) {
    motion = Compose(motion,
                     EncoderStepDisplacement(wheel_radius_m, wheelbase_m, delta_r, delta_l, delta_b,
                                             it->left_rad - left, it->right_rad - right));
    left = Time(it->left_rad);
    right = Time(it->right_rad);
  }
  return Compose(motion, EncoderStepDisplacement(wheel_radius_m, wheelbase_m, delta_r, delta_l,
                                                 delta_b, left_end - left, right_end - right));
}

// First-order covariance of IntegrateEncoders' displacement when each encoder increment Δα is
// read with variance K²/r·|Δα| (§8.1, after Chong and Kleeman), independently per wheel and step.
inline Eigen::Matrix3d EncoderDisplacementCovariance(const std::vector<EncoderSample>& odometry,
                                                     double t0_s, double t1_s,
                                                     double wheel_radius_m, double wheelbase_m,
                                                     double delta_r, double delta_l, double delta_b,
                                                     double k_left, double k_right) {
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  if (odometry.empty()) return cov;
  if (t1_s < t0_s) std::swap(t0_s, t1_s);  // The inverse has the same uncertainty up to frame.
  Pose2d pose = Pose2d::Zero();
  const auto step = [&](double d_left, double d_right) {
    const double r = wheel_radius_m;
    const double dist = 0.5 * r * (delta_r * d_right + delta_l * d_left);
    const double ang = r * (delta_r * d_right - delta_l * d_left) / (delta_b * wheelbase_m);
    // The arc u = Exp(dist, 0, ang) and ∂u/∂(dist, ang): columns 0 and 2 of ∂Exp/∂ξ.
    const Twist2d twist(dist, 0.0, ang);
    const Eigen::Vector3d u = Exp(twist);
    const Eigen::Matrix3d d_exp = ExpJacobian(twist);
    Eigen::Matrix<double, 3, 2> du_dda;
    du_dda << d_exp.col(0), d_exp.col(2);
    Eigen::Matrix2d dda_dw;  // ∂(dist, ang)/∂(Δα_R, Δα_L).
    dda_dw << 0.5 * r * delta_r, 0.5 * r * delta_l, r * delta_r / (delta_b * wheelbase_m),
        -r * delta_l / (delta_b * wheelbase_m);
    const Eigen::Matrix<double, 3, 2> du_dw = du_dda * dda_dw;
    const Eigen::Vector2d var(k_right * k_right / r * std::abs(d_right),
                              k_left * k_left / r * std::abs(d_left));
    const double ct = std::cos(pose(2)), st = std::sin(pose(2));
    Eigen::Matrix3d j_pose = Eigen::Matrix3d::Identity();
    j_pose(0, 2) = -st * u(0) - ct * u(1);
    j_pose(1, 2) = ct * u(0) - st * u(1);
    Eigen::Matrix3d j_step = Eigen::Matrix3d::Identity();
    j_step.topLeftCorner<2, 2>() << ct, -st, st, ct;
    const Eigen::Matrix<double, 3, 2> j_wheels = j_step * du_dw;
    cov = j_pose * cov * j_pose.transpose() + j_wheels * var.asDiagonal() * j_wheels.transpose();
    pose = Compose(pose, Pose2d(u));
  };
  double left = 0.0, right = 0.0, left_end = 0.0, right_end = 0.0;
  InterpolateWheelAngles(odometry, t0_s, &left, &right);
  InterpolateWheelAngles(odometry, t1_s, &left_end, &right_end);
  auto it = std::upper_bound(odometry.begin(), odometry.end(), t0_s,
                             [](double t, const EncoderSample& sample) { return t < sample.t_s; });
  for (; it != odometry.end() && it->t_s < t1_s; ++it) {
    step(it->left_rad - left, it->right_rad - right);
    left = it->left_rad;
    right = it->right_rad;
  }
  step(left_end - left, right_end - right);
  return cov;
}

// The robot displacement through a sequence of cumulative wheel angles (left, right), each step a
// constant-speed arc (Censi §II-D): time drops out, only the angle increments matter.
template <typename T>
Pose2<T> WheelAngleChainDisplacement(const T& left_radius, const T& right_radius,
                                     const T& wheelbase, const T* left_rad, const T* right_rad,
                                     int count) {
  Pose2<T> motion = Pose2<T>::Zero();
  for (int i = 1; i < count; ++i) {
    motion = Compose(motion, WheelStepDisplacement(left_radius, right_radius, wheelbase,
                                                   T(left_rad[i] - left_rad[i - 1]),
                                                   T(right_rad[i] - right_rad[i - 1])));
  }
  return motion;
}

}  // namespace calib

#endif  // CALIB_CORE_TIMING_ENCODER_INTEGRATION_H_
