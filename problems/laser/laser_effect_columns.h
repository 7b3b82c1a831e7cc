#ifndef CALIB_PROBLEMS_LASER_LASER_EFFECT_COLUMNS_H_
#define CALIB_PROBLEMS_LASER_LASER_EFFECT_COLUMNS_H_

#include <calib/core/laser/laser_params.h>
#include <calib/core/se2.h>
#include <calib/core/sin_cos.h>
#include <calib/problems/laser/laser_effect_residual.h>
#include <calib/problems/laser/laser_residual.h>

#include <Eigen/Core>
#include <cmath>

// LaserEffectResidual's derivatives in γ at γ = 0 in closed form, for the score tests' base
// evaluation: per interval a few products where automatic derivatives in nine directions cost
// microseconds.
namespace calib {

namespace effect_columns_internal {

// (v, ω) at γ = 0 for wheel speeds φ.
inline Eigen::Vector2d BaseTwist(const double* odometry, const Eigen::Vector2d& speed) {
  return Eigen::Vector2d((odometry[0] * speed(0) + odometry[1] * speed(1)) / 2.0,
                         (odometry[1] * speed(1) - odometry[0] * speed(0)) / odometry[2]);
}

// First-order change of o when a small pose (x, y, θ) is composed before it (X ∘ o) or after
// it (o ∘ X): (x − θ·o_y, y + θ·o_x, θ) and (R(o_θ)·(x, y), θ).
inline Eigen::Vector3d Before(const Eigen::Vector3d& motion, double x, double y, double theta) {
  return Eigen::Vector3d(x - theta * motion(1), y + theta * motion(0), theta);
}
inline Eigen::Vector3d After(double cos_turn, double sin_turn, double x, double y, double theta) {
  return Eigen::Vector3d(cos_turn * x - sin_turn * y, sin_turn * x + cos_turn * y, theta);
}

}  // namespace effect_columns_internal

// On a constant-speed interval whose radii do not change inside it, at γ = 0: the residual r, the
// base columns (LaserResidual's) and the nine effect columns ∂r/∂γ = −L·∂s/∂γ. With o = Exp(d, 0,
// a) the robot motion and M = ∂s/∂o (s_p = R(−ℓ_θ)·[o_p + (R(o_θ) − I)·ℓ_p], s_θ = o_θ), each
// motion effect adds δo to first order (see EffectRobotMotion):
//   time offset: Arc(−m_s) before o, Arc(m_e) after (m the boundary's mean twist; ε: its half
//     difference h); longitudinal slip: (m_s,v − v, 0, 0) before, (v − m_e,v, 0, 0) after;
//   lateral slip: ∂Exp/∂ξ_y·d·a/T = (−C, S, 0)·d·a/T; ICR offset: (1, 0, 0) before, (−1, 0, 0)
//   after;
// and the radius effects scale ∂s/∂r_i: r_i after the change (γ_change,i), r_i·(|φ_i| − φ_ref)
// (γ_speed); the scan scale adds (s_x, s_y, 0). Returns false (nothing written) for a stepped
// interval or a change inside the interval: operator() by automatic derivatives then.
inline bool EffectColumnsAtZero(
    const LaserEffectContext& context, const Eigen::Matrix3d& sqrt_information,
    const double* odometry, const SensorMounting& mounting, Eigen::Vector3d* r,
    Eigen::Matrix<double, 3, kNumLaserParams>* j_base,
    Eigen::Matrix<double, 3, kNumLaserEffectParams, Eigen::RowMajor>* j_effects) {
  using namespace effect_columns_internal;  // NOLINT: this header's helpers.
  const LaserInterval& interval = *context.interval;
  const double duration = interval.duration_s;
  const bool changed = context.change_offset_s <= 0.0;
  if (!interval.steps.empty() || (!changed && context.change_offset_s < duration)) return false;
  Eigen::Vector3d error;
  Eigen::Matrix<double, 3, kNumLaserParams> ds_dp;
  LaserResidual::ConstantSpeedError(interval, odometry, mounting, &error, &ds_dp);

  const Eigen::Vector2d speed(interval.left_speed, interval.right_speed);
  const Eigen::Vector2d twist = BaseTwist(odometry, speed);
  const double d = twist(0) * duration, a = twist(1) * duration;
  double sin_a, cos_a;
  SinCos(a, &sin_a, &cos_a);
  double s, c;
  ArcCoefficients(a, sin_a, cos_a, &s, &c);
  const Eigen::Vector3d motion(s * d, c * d, a);
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();  // ∂s/∂o.
  const double cl = mounting.cos_theta, sl = mounting.sin_theta;
  const Eigen::Matrix2d to_sensor = (Eigen::Matrix2d() << cl, sl, -sl, cl).finished();
  const double* mount = mounting.pose;
  m.topLeftCorner<2, 2>() = to_sensor;
  m.block<2, 1>(0, 2) = to_sensor * Eigen::Vector2d(-sin_a * mount[0] - cos_a * mount[1],
                                                    cos_a * mount[0] - sin_a * mount[1]);
  m(2, 2) = 1.0;

  const auto mean = [&](const BoundarySpeeds& b) {
    return Eigen::Vector2d((BaseTwist(odometry, b.before) + BaseTwist(odometry, b.after)) / 2.0);
  };
  const auto half = [&](const BoundarySpeeds& b) {
    return Eigen::Vector2d((BaseTwist(odometry, b.after) - BaseTwist(odometry, b.before)) / 2.0);
  };
  const Eigen::Vector2d m_start = mean(context.start), m_end = mean(context.end);
  const Eigen::Vector2d h_start = half(context.start), h_end = half(context.end);
  const auto window = [&](const Eigen::Vector2d& at_start, const Eigen::Vector2d& at_end) {
    return Eigen::Vector3d(Before(motion, -at_start(0), 0.0, -at_start(1)) +
                           After(cos_a, sin_a, at_end(0), 0.0, at_end(1)));
  };
  Eigen::Matrix<double, 3, kNumLaserEffectParams> ds_dgamma;
  const auto column = [&](LaserEffect effect) { return EffectInfo(effect).offset; };
  ds_dgamma.col(column(LaserEffect::kTimeOffset)) = m * window(m_start, m_end);
  ds_dgamma.col(kTimeOffsetAsymmetryIndex) = m * window(h_start, h_end);
  const double lateral = d * a / duration;
  ds_dgamma.col(column(LaserEffect::kLateralSlip)) = m * Eigen::Vector3d(-c, s, 0.0) * lateral;
  ds_dgamma.col(column(LaserEffect::kLongitudinalSlip)) =
      m * (Before(motion, m_start(0) - twist(0), 0.0, 0.0) +
           After(cos_a, sin_a, twist(0) - m_end(0), 0.0, 0.0));
  const int change = column(LaserEffect::kWheelRadiusChange);
  for (int i = 0; i < 2; ++i) {
    ds_dgamma.col(change + i) =
        changed ? Eigen::Vector3d(odometry[i] * ds_dp.col(i)) : Eigen::Vector3d::Zero();
  }
  const double reference = context.reference_speed;
  ds_dgamma.col(column(LaserEffect::kSpeedDependentRadius)) =
      odometry[0] * (std::abs(speed(0)) - reference) * ds_dp.col(0) +
      odometry[1] * (std::abs(speed(1)) - reference) * ds_dp.col(1);
  ds_dgamma.col(column(LaserEffect::kIcrOffset)) = m * Eigen::Vector3d(1.0 - cos_a, -sin_a, 0.0);
  const Pose2d& measured = interval.sensor_motion;
  ds_dgamma.col(column(LaserEffect::kScanScale)) =
      Eigen::Vector3d(measured(0) - error(0), measured(1) - error(1), 0.0);

  *r = sqrt_information * error;
  *j_base = -sqrt_information * ds_dp;
  *j_effects = -sqrt_information * ds_dgamma;
  return true;
}

}  // namespace calib

#endif  // CALIB_PROBLEMS_LASER_LASER_EFFECT_COLUMNS_H_
