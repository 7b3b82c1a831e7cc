#ifndef CALIB_PROBLEMS_LASER_LASER_EFFECT_RESIDUAL_H_
#define CALIB_PROBLEMS_LASER_LASER_EFFECT_RESIDUAL_H_

#include <calib/core/diff_drive.h>
#include <calib/core/laser/laser_log.h>
#include <calib/core/se2.h>
#include <calib/problems/laser/laser_effect_context.h>
#include <calib/problems/laser/laser_residual.h>
#include <ceres/autodiff_cost_function.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

// Candidate effects that the base laser–odometry model (problems/laser_residual.h) leaves out,
// each with its own parameter γ; at γ = 0 the residual is exactly the base residual, so autodiff
// at γ = 0 gives each effect's sensitivity for the score tests of `calib diagnose`.
namespace calib {

enum class LaserEffect {
  kTimeOffset = 0,     // A scan stamped t was taken at t + γ (s) on the odometry clock.
  kLateralSlip,        // Lateral velocity = γ·v·ω (s), +y left.
  kLongitudinalSlip,   // Forward velocity = v − γ·dv/dt (s).
  kWheelRadiusChange,  // After a change time t_c the radii are r_l·(1 + γ_l), r_r·(1 + γ_r).
  kSpeedDependentRadius,  // Effective radius r·(1 + γ·(|φ| − φ_ref)) of each wheel (γ in s/rad).
  kIcrOffset,             // The no-slip point (ICR line) sits at x = γ (m) in the robot frame.
  kScanScale,             // The scan matcher reports translations scaled by (1 + γ).
};
inline constexpr int kNumLaserEffects = 7;
inline constexpr int kNumLaserEffectParams = 9;  // Length of the effect parameter block.
// Not an effect: ε in the time offset's window ends, δ·m + (|δ| + ε)·h (m, h the mean and half
// difference of the one-sided twists), for testing the piecewise-constant model's |δ|·h term
// (ε = 0) against data whose speed jumps it might fit for another reason.
inline constexpr int kTimeOffsetAsymmetryIndex = 8;

struct LaserEffectInfo {
  const char* name;  // The contract's effect name.
  const char* unit;  // Of γ.
  int offset;        // First entry of γ in the effect parameter block.
  int size;          // Number of entries.
};
inline constexpr std::array<LaserEffectInfo, kNumLaserEffects> kLaserEffectInfo = {{
    {"time_offset", "s", 0, 1},
    {"lateral_slip", "s", 1, 1},
    {"longitudinal_slip", "s", 2, 1},
    {"wheel_radius_change", "1", 3, 2},
    {"speed_dependent_radius", "s/rad", 5, 1},
    {"icr_offset_x", "m", 6, 1},
    {"scan_scale", "1", 7, 1},
}};
inline const LaserEffectInfo& EffectInfo(LaserEffect effect) {
  return kLaserEffectInfo[static_cast<int>(effect)];
}

namespace effect_internal {

// Wheel radii in effect for wheel speeds φ: r·(1 + γ_s·(|φ| − φ_ref))·(1 + γ_c after the change).
template <typename T>
Eigen::Matrix<T, 2, 1> Radii(const T* odometry, const T* gamma, const Eigen::Vector2d& speed,
                             bool changed, double reference_speed) {
  const LaserEffectInfo& speed_info = EffectInfo(LaserEffect::kSpeedDependentRadius);
  const LaserEffectInfo& change_info = EffectInfo(LaserEffect::kWheelRadiusChange);
  Eigen::Matrix<T, 2, 1> radii;
  for (int i = 0; i < 2; ++i) {
    radii(i) =
        odometry[i] * (T(1) + gamma[speed_info.offset] * (std::abs(speed(i)) - reference_speed));
    if (changed) radii(i) = radii(i) * (T(1) + gamma[change_info.offset + i]);
  }
  return radii;
}

// (v, ω) for wheel speeds φ.
template <typename T>
Eigen::Matrix<T, 2, 1> Twist(const T* odometry, const T* gamma, const Eigen::Vector2d& speed,
                             bool changed, double reference_speed) {
  const Eigen::Matrix<T, 2, 1> r = Radii(odometry, gamma, speed, changed, reference_speed);
  return Eigen::Matrix<T, 2, 1>((r(0) * speed(0) + r(1) * speed(1)) / T(2),
                                (r(1) * speed(1) - r(0) * speed(0)) / odometry[2]);
}

template <typename T>
T Sign(const T& x) {
  return x > T(0) ? T(1) : (x < T(0) ? T(-1) : T(0));
}

// Wheel speeds (φ_l, φ_r) of a constant-speed step (zero for an empty step).
inline Eigen::Vector2d StepSpeed(const WheelStep& step) {
  return step.duration_s > 0.0
             ? Eigen::Vector2d(step.left_rad / step.duration_s, step.right_rad / step.duration_s)
             : Eigen::Vector2d::Zero();
}

// Π_j Exp(ξ_j·Δt_j) over the pieces of constant wheel speed (the steps, split at the radius
// change `change` s after the interval start), with the full longitudinal impulse at each speed
// jump between steps (see EffectRobotMotion).
template <typename T>
Pose2<T> PiecesMotion(const T* odometry, const T* gamma, const WheelStep* steps, size_t num_steps,
                      double change, double reference, const T& lateral, const T& longitudinal) {
  Pose2<T> core = Pose2<T>::Zero();
  double t = 0.0;  // Since the interval start.
  for (size_t j = 0; j < num_steps; ++j) {
    const WheelStep& step = steps[j];
    const Eigen::Vector2d speed = StepSpeed(step);
    if (j > 0) {
      // A speed jump inside the interval: the full impulse, with the radii of that instant.
      const bool changed = t >= change;
      const T jump = Twist(odometry, gamma, speed, changed, reference)(0) -
                     Twist(odometry, gamma, StepSpeed(steps[j - 1]), changed, reference)(0);
      core = Compose(core, Pose2<T>(-longitudinal * jump, T(0), T(0)));
    }
    // The step's share before the radius change (1: no change inside this step).
    double before_share = 1.0;
    if (change < t + step.duration_s) {
      before_share = change <= t ? 0.0 : (change - t) / step.duration_s;
    }
    for (int part = 0; part < 2; ++part) {
      const double share = part == 0 ? before_share : 1.0 - before_share;
      if (share <= 0.0) continue;
      const Eigen::Matrix<T, 2, 1> radii =
          effect_internal::Radii(odometry, gamma, speed, part == 1, reference);
      const T left_rad(share == 1.0 ? step.left_rad : step.left_rad * share);
      const T right_rad(share == 1.0 ? step.right_rad : step.right_rad * share);
      const T along = (radii(0) * left_rad + radii(1) * right_rad) / T(2);
      const T angle = (radii(1) * right_rad - radii(0) * left_rad) / odometry[2];
      const double dt = step.duration_s * share;
      // Lateral travel γ·v·ω·Δt = γ·along·angle/Δt.
      const T across = dt > 0.0 ? lateral * along * angle / T(dt) : T(0);
      core = Compose(core, Exp(Twist2<T>(along, across, angle)));
    }
    t += step.duration_s;
  }
  return core;
}

}  // namespace effect_internal

// The robot displacement over an interval with the candidate effects γ (the effect block):
//   o(γ) = P ∘ Exp(−δ·ξ_s) ∘ I_s ∘ Π_j Exp(ξ_j·Δt_j) ∘ I_e ∘ Exp(δ·ξ_e) ∘ P⁻¹
// - pieces j of constant wheel speed (the interval, or its steps, split at the radius change):
//   v, ω from radii r_i·(1 + γ_speed·(|φ_i| − φ_ref))·(1 + γ_change,i after t_c), body twist
//   ξ_j = (v, γ_lat·v·ω, ω);
// - longitudinal slip, forward velocity v − γ_long·dv/dt: a forward impulse −γ_long·Δv at each
//   speed jump; at the interval ends I_s = γ_long·(v_b(t_k) − v_first), I_e = γ_long·(v_last −
//   v_b(t_{k+1})), with v_b the boundary speed (for a jump the mean of both sides: a scan at the
//   jump sees half of it, the simulator's convention);
// - time offset δ: the window [t_k + δ, t_{k+1} + δ]; ξ_s, ξ_e the twists at the window ends,
//   (before + after)/2 + sign(δ)·(after − before)/2, i.e. the one-sided speeds (exact for
//   piecewise-constant speeds) with the centred derivative at δ = 0 (ε: see above);
// - ICR offset: P = (γ_icr, 0, 0) moves the reference point to the no-slip point.
// Combinations are first-order accurate (cross terms such as γ_long·δ are left out).
template <typename T>
Pose2<T> EffectRobotMotion(const T* odometry, const T* gamma, const LaserEffectContext& context) {
  using effect_internal::Sign;
  using effect_internal::Twist;
  const LaserInterval& interval = *context.interval;
  const T& time_offset = gamma[EffectInfo(LaserEffect::kTimeOffset).offset];
  const T& lateral = gamma[EffectInfo(LaserEffect::kLateralSlip).offset];
  const T& longitudinal = gamma[EffectInfo(LaserEffect::kLongitudinalSlip).offset];
  const T& icr = gamma[EffectInfo(LaserEffect::kIcrOffset).offset];
  const double change = context.change_offset_s;
  const double reference = context.reference_speed;

  const WheelStep single{interval.duration_s, interval.left_speed * interval.duration_s,
                         interval.right_speed * interval.duration_s};
  const WheelStep* steps = interval.steps.empty() ? &single : interval.steps.data();
  const size_t num_steps = interval.steps.empty() ? 1 : interval.steps.size();
  const Pose2<T> core = effect_internal::PiecesMotion(odometry, gamma, steps, num_steps, change,
                                                      reference, lateral, longitudinal);

  // Boundary speeds and the impulses at the interval ends.
  const bool changed_start = change <= 0.0;
  const bool changed_end = change <= interval.duration_s;
  const auto boundary_forward = [&](const BoundarySpeeds& b, bool changed) {
    return (Twist(odometry, gamma, b.before, changed, reference)(0) +
            Twist(odometry, gamma, b.after, changed, reference)(0)) /
           T(2);
  };
  const T v_first =
      Twist(odometry, gamma, effect_internal::StepSpeed(steps[0]), changed_start, reference)(0);
  const T v_last = Twist(odometry, gamma, effect_internal::StepSpeed(steps[num_steps - 1]),
                         changed_end, reference)(0);
  const Pose2<T> impulse_start(
      longitudinal * (boundary_forward(context.start, changed_start) - v_first), T(0), T(0));
  const Pose2<T> impulse_end(longitudinal * (v_last - boundary_forward(context.end, changed_end)),
                             T(0), T(0));
  Pose2<T> motion = Compose(Compose(impulse_start, core), impulse_end);

  // The shifted window: the twist at each end is m ± h (one-sided speeds after/before), so the
  // window moves by δ·m + |δ|·h (+ ε·h), |δ| = sign(δ)·δ (derivative 0 at δ = 0: centred).
  const T magnitude = Sign(time_offset) * time_offset + gamma[kTimeOffsetAsymmetryIndex];
  const auto window_shift = [&](const BoundarySpeeds& b, bool changed) {
    const Eigen::Matrix<T, 2, 1> before = Twist(odometry, gamma, b.before, changed, reference);
    const Eigen::Matrix<T, 2, 1> after = Twist(odometry, gamma, b.after, changed, reference);
    return Eigen::Matrix<T, 2, 1>(time_offset * (before + after) / T(2) +
                                  magnitude * (after - before) / T(2));
  };
  const Eigen::Matrix<T, 2, 1> shift_start = window_shift(context.start, changed_start);
  const Eigen::Matrix<T, 2, 1> shift_end = window_shift(context.end, changed_end);
  motion = Compose(ArcDisplacement(T(-shift_start(0)), T(-shift_start(1))),
                   Compose(motion, ArcDisplacement(shift_end(0), shift_end(1))));

  // The ICR offset: the same motion seen from a reference point moved by (γ_icr, 0).
  const Pose2<T> icr_point(icr, T(0), T(0));
  return Compose(Compose(icr_point, motion), Inverse(icr_point));
}

// The base residual (problems/laser_residual.h) with the candidate effects:
//   ŝ_pred = D(γ_scale)·(ℓ⁻¹ ∘ o(γ) ∘ ℓ),  D = diag(1 + γ_scale, 1 + γ_scale, 1),
//   r = L·SensorMotionError(ŝ_pred, ŝ)  (the base's error, whatever its form).
// Parameter blocks: odometry (r_l, r_r, b), base_T_sensor (x, y, θ), effects γ
// (kNumLaserEffectParams, layout kLaserEffectInfo). The context (and its interval) and
// `sqrt_information` are held by pointer and must outlive the cost function.
class LaserEffectResidual {
 public:
  LaserEffectResidual(const LaserEffectContext& context, const Eigen::Matrix3d* sqrt_information)
      : context_(&context), sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* const odometry, const T* const base_T_sensor, const T* const effects,
                  T* residual) const {
    const Pose2<T> robot_motion = EffectRobotMotion(odometry, effects, *context_);
    const Pose2<T> mounting(base_T_sensor[0], base_T_sensor[1], base_T_sensor[2]);
    Pose2<T> predicted = SensorMotionFromRobotMotion(mounting, robot_motion);
    const T scale = T(1) + effects[EffectInfo(LaserEffect::kScanScale).offset];
    predicted(0) = predicted(0) * scale;
    predicted(1) = predicted(1) * scale;
    const Eigen::Matrix<T, 3, 1> error =
        SensorMotionError(predicted, context_->interval->sensor_motion);
    Eigen::Map<Eigen::Matrix<T, 3, 1>> whitened(residual);
    whitened = sqrt_information_->cast<T>() * error;
    return true;
  }

  static ceres::CostFunction* Create(const LaserEffectContext& context,
                                     const Eigen::Matrix3d* sqrt_information) {
    return new ceres::AutoDiffCostFunction<LaserEffectResidual, 3, 3, 3, kNumLaserEffectParams>(
        new LaserEffectResidual(context, sqrt_information));
  }

 private:
  const LaserEffectContext* context_;
  const Eigen::Matrix3d* sqrt_information_;
};

}  // namespace calib

#endif  // CALIB_PROBLEMS_LASER_LASER_EFFECT_RESIDUAL_H_
