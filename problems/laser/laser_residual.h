#ifndef CALIB_PROBLEMS_LASER_LASER_RESIDUAL_H_
#define CALIB_PROBLEMS_LASER_LASER_RESIDUAL_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/se2.h>
#include <calib/core/sin_cos.h>
#include <ceres/autodiff_cost_function.h>
#include <ceres/jet.h>

#include <Eigen/Core>
#include <cmath>

namespace calib {

// The mismatch ŝ ⊖ ŝ_pred between a measured and a predicted sensor displacement, expressed in
// the sensor frame at the interval start, where the scan matcher reports ŝ and its noise lives:
//   e = R(ŝ_pred,θ)·(ŝ_pred⁻¹ ∘ ŝ)_xy , wrap(ŝ_θ − ŝ_pred,θ)  =  (ŝ_xy − ŝ_pred,xy, wrap(ŝ_θ −
//   ŝ_pred,θ)).
// (Whitening ŝ_pred⁻¹ ∘ ŝ itself would apply an anisotropic noise model in a frame rotated by
// ŝ_pred,θ.)
template <typename T>
Eigen::Matrix<T, 3, 1> SensorMotionError(const Pose2<T>& predicted, const Pose2d& measured) {
  return Eigen::Matrix<T, 3, 1>(T(measured(0)) - predicted(0), T(measured(1)) - predicted(1),
                                WrapAngle(T(measured(2)) - predicted(2)));
}

// base_T_sensor = (x, y, θ) with the sine and cosine of θ: computed once per pass over the
// intervals rather than once per interval (a tenth of the closed-form linearization's time).
struct SensorMounting {
  explicit SensorMounting(const double* base_T_sensor)
      : pose(base_T_sensor),
        cos_theta(std::cos(base_T_sensor[2])),
        sin_theta(std::sin(base_T_sensor[2])) {}
  const double* pose;
  double cos_theta, sin_theta;
};

// Pose-composition residual of one laser interval (Censi eq. 9 as a measurement model):
//   ŝ_pred = ℓ⁻¹ ∘ o(Δφ_l, Δφ_r; r_l, r_r, b) ∘ ℓ,   r = L·SensorMotionError(ŝ_pred, ŝ),
// with LᵀL the information of the scan-matching noise.
// Parameter blocks: odometry = (r_l, r_r, b), base_T_sensor = (x, y, θ).
// The interval and `sqrt_information` are held by pointer (a million intervals are not copied, and
// a re-estimated noise level applies without rebuilding the problem); both must outlive the cost
// function.
class LaserResidual {
 public:
  LaserResidual(const LaserInterval& interval, const Eigen::Matrix3d* sqrt_information)
      : interval_(&interval), sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* const odometry, const T* const base_T_sensor, T* residual) const {
    const Pose2<T> robot_motion =
        IntervalRobotMotion(odometry[0], odometry[1], odometry[2], *interval_);
    const Pose2<T> mounting(base_T_sensor[0], base_T_sensor[1], base_T_sensor[2]);
    const Pose2<T> predicted = SensorMotionFromRobotMotion(mounting, robot_motion);
    const Eigen::Matrix<T, 3, 1> error = SensorMotionError(predicted, interval_->sensor_motion);
    Eigen::Map<Eigen::Matrix<T, 3, 1>> whitened(residual);
    whitened = sqrt_information_->cast<T>() * error;
    return true;
  }

  // Unwhitened error e for given parameters, for noise estimation and diagnostics.
  static Eigen::Vector3d Error(const LaserInterval& interval, const double* odometry,
                               const double* base_T_sensor) {
    return Error(interval, odometry, SensorMounting(base_T_sensor));
  }
  static Eigen::Vector3d Error(const LaserInterval& interval, const double* odometry,
                               const SensorMounting& mounting) {
    Eigen::Vector3d error;
    if (interval.steps.empty()) {
      ConstantSpeedError(interval, odometry, mounting, &error, nullptr);
    } else {
      const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
      LaserResidual(interval, &identity)(odometry, mounting.pose, error.data());
    }
    return error;
  }

  // Whitened residual r = L·e at the given parameters (as operator(); a constant-speed interval
  // by the closed form below).
  static void Evaluate(const LaserInterval& interval, const Eigen::Matrix3d& sqrt_information,
                       const double* odometry, const double* base_T_sensor, Eigen::Vector3d* r) {
    Evaluate(interval, sqrt_information, odometry, SensorMounting(base_T_sensor), r);
  }
  static void Evaluate(const LaserInterval& interval, const Eigen::Matrix3d& sqrt_information,
                       const double* odometry, const SensorMounting& mounting, Eigen::Vector3d* r) {
    if (interval.steps.empty()) {
      Eigen::Vector3d error;
      ConstantSpeedError(interval, odometry, mounting, &error, nullptr);
      *r = sqrt_information * error;
    } else {
      LaserResidual(interval, &sqrt_information)(odometry, mounting.pose, r->data());
    }
  }

  // Whitened residual r and its Jacobian J = ∂r/∂(r_l, r_r, b, x, y, θ) (3×6) at the given
  // parameters, without a cost-function object: the fused passes and the covariances call it
  // once per interval. A constant-speed interval has it in closed form (below); a stepped one
  // by forward-mode differentiation.
  static void Linearize(const LaserInterval& interval, const Eigen::Matrix3d& sqrt_information,
                        const double* odometry, const double* base_T_sensor, Eigen::Vector3d* r,
                        Eigen::Matrix<double, 3, 6>* jacobian) {
    Linearize(interval, sqrt_information, odometry, SensorMounting(base_T_sensor), r, jacobian);
  }
  static void Linearize(const LaserInterval& interval, const Eigen::Matrix3d& sqrt_information,
                        const double* odometry, const SensorMounting& mounting, Eigen::Vector3d* r,
                        Eigen::Matrix<double, 3, 6>* jacobian) {
    const double* base_T_sensor = mounting.pose;
    if (interval.steps.empty()) {
      Eigen::Vector3d error;
      Eigen::Matrix<double, 3, 6> sensor_motion_jacobian;
      ConstantSpeedError(interval, odometry, mounting, &error, &sensor_motion_jacobian);
      if (IsDiagonal(sqrt_information)) {
        // A noise level per component (the base fit's whitening): rows scaled, the full
        // product's values (its other terms add zeros) in a fraction of its operations.
        const Eigen::Vector3d scale = sqrt_information.diagonal();
        *r = scale.cwiseProduct(error);
        *jacobian = -(scale.asDiagonal() * sensor_motion_jacobian);
      } else {
        *r = sqrt_information * error;
        *jacobian = -sqrt_information * sensor_motion_jacobian;
      }
      return;
    }
    using Jet = ceres::Jet<double, 6>;
    Jet odometry_jet[3], sensor_jet[3], residual[3];
    for (int i = 0; i < 3; ++i) {
      odometry_jet[i] = Jet(odometry[i], i);
      sensor_jet[i] = Jet(base_T_sensor[i], 3 + i);
    }
    LaserResidual(interval, &sqrt_information)(odometry_jet, sensor_jet, residual);
    for (int row = 0; row < 3; ++row) {
      (*r)(row) = residual[row].a;
      jacobian->row(row) = residual[row].v.transpose();
    }
  }

  static bool IsDiagonal(const Eigen::Matrix3d& m) {
    return m(1, 0) == 0.0 && m(2, 0) == 0.0 && m(0, 1) == 0.0 && m(2, 1) == 0.0 && m(0, 2) == 0.0 &&
           m(1, 2) == 0.0;
  }

  static ceres::CostFunction* Create(const LaserInterval& interval,
                                     const Eigen::Matrix3d* sqrt_information) {
    return new ceres::AutoDiffCostFunction<LaserResidual, 3, 3, 3>(
        new LaserResidual(interval, sqrt_information));
  }

  // The wheels turn by φ = (φ_l, φ_r); the arc has length d = (r_l·φ_l + r_r·φ_r)/2 and angle
  // a = (r_r·φ_r − r_l·φ_l)/b, o = (S·d, C·d, a) (S, C as in Exp), and with ℓ = (ℓ_p, ℓ_θ)
  //   s_p = R(−ℓ_θ)·[o_p + (R(a) − I)·ℓ_p],  s_θ = a,  e = ŝ − s (θ wrapped),  r = L·e, J = −L·∂s.
  //   ∂s_p/∂d = R(−ℓ_θ)·(S, C),  ∂s_p/∂a = R(−ℓ_θ)·[(S', C')·d + R'(a)·ℓ_p],  ∂s_θ/∂a = 1,
  //   ∂s_p/∂ℓ_p = R(−ℓ_θ)·(R(a) − I),  ∂s_p/∂ℓ_θ = (s_y, −s_x),
  //   ∂(d, a)/∂(r_l, r_r, b) = [[φ_l/2, φ_r/2, 0], [−φ_l/b, φ_r/b, −a/b]].
  // Fills e and, when `ds_dp` is not null, ∂s/∂(r_l, r_r, b, x, y, θ).
  static void ConstantSpeedError(const LaserInterval& interval, const double* odometry,
                                 const SensorMounting& mounting, Eigen::Vector3d* error,
                                 Eigen::Matrix<double, 3, 6>* ds_dp) {
    const double* base_T_sensor = mounting.pose;
    const double left = interval.left_speed * interval.duration_s;
    const double right = interval.right_speed * interval.duration_s;
    const double rl = odometry[0], rr = odometry[1], b = odometry[2];
    const double d = (rl * left + rr * right) / 2.0;
    const double a = (rr * right - rl * left) / b;
    // One sine and cosine of the arc serve S, C, the turn and their derivatives.
    double sa, ca;
    SinCos(a, &sa, &ca);
    double s, c;
    ArcCoefficients(a, sa, ca, &s, &c);
    // In scalars (the pass's innermost work; Eigen's 2×2 temporaries cost a third more).
    const double cl = mounting.cos_theta, sl = mounting.sin_theta;
    const double mx = base_T_sensor[0], my = base_T_sensor[1];
    // w = (S·d, C·d) + (R(a) − I)·ℓ_p, s_p = R(−ℓ_θ)·w.
    const double wx = s * d + (ca * mx - sa * my) - mx;
    const double wy = c * d + (sa * mx + ca * my) - my;
    const double sensor_x = cl * wx + sl * wy, sensor_y = cl * wy - sl * wx;
    const Pose2d& measured = interval.sensor_motion;
    // s_θ as the composition rounds it, (a + ℓ_θ) − ℓ_θ, so that e equals operator()'s.
    const double sensor_theta = (a + base_T_sensor[2]) - base_T_sensor[2];
    *error = Eigen::Vector3d(measured(0) - sensor_x, measured(1) - sensor_y,
                             WrapAngle(measured(2) - sensor_theta));
    if (ds_dp == nullptr) return;
    double ds, dc;
    if (std::abs(a) < kSe2SmallAngle) {
      ArcCoefficientDerivatives(a, sa, ca, &ds, &dc);
    } else {
      // As ArcCoefficientDerivatives, by one reciprocal instead of two divisions.
      const double inverse_a2 = 1.0 / (a * a);
      ds = (a * ca - sa) * inverse_a2;
      dc = (a * sa - 1.0 + ca) * inverse_a2;
    }
    // ∂s_p/∂d = R(−ℓ_θ)·(S, C) and ∂s_p/∂a = R(−ℓ_θ)·u, u = (S', C')·d + R'(a)·ℓ_p.
    const double by_d_x = cl * s + sl * c, by_d_y = cl * c - sl * s;
    const double ux = ds * d - sa * mx - ca * my, uy = dc * d + ca * mx - sa * my;
    const double by_a_x = cl * ux + sl * uy, by_a_y = cl * uy - sl * ux;
    const double inverse_b = 1.0 / b;
    const double left_d = left / 2.0, left_a = left * inverse_b, right_d = right / 2.0,
                 right_a = right * inverse_b, b_a = a * inverse_b;
    Eigen::Matrix<double, 3, 6>& m = *ds_dp;
    m(0, 0) = by_d_x * left_d - by_a_x * left_a;
    m(1, 0) = by_d_y * left_d - by_a_y * left_a;
    m(2, 0) = -left_a;
    m(0, 1) = by_d_x * right_d + by_a_x * right_a;
    m(1, 1) = by_d_y * right_d + by_a_y * right_a;
    m(2, 1) = right_a;
    m(0, 2) = -by_a_x * b_a;
    m(1, 2) = -by_a_y * b_a;
    m(2, 2) = -b_a;
    // ∂s_p/∂ℓ_p = R(−ℓ_θ)·(R(a) − I), ∂s_p/∂ℓ_θ = (s_y, −s_x).
    const double cm = ca - 1.0;
    m(0, 3) = cl * cm + sl * sa;
    m(0, 4) = sl * cm - cl * sa;
    m(1, 3) = cl * sa - sl * cm;
    m(1, 4) = sl * sa + cl * cm;
    m(2, 3) = 0.0;
    m(2, 4) = 0.0;
    m(0, 5) = sensor_y;
    m(1, 5) = -sensor_x;
    m(2, 5) = 0.0;
  }

 private:
  const LaserInterval* interval_;
  const Eigen::Matrix3d* sqrt_information_;
};

}  // namespace calib

#endif  // CALIB_PROBLEMS_LASER_LASER_RESIDUAL_H_
