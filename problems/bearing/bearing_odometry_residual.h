#ifndef CALIB_PROBLEMS_BEARING_BEARING_ODOMETRY_RESIDUAL_H_
#define CALIB_PROBLEMS_BEARING_BEARING_ODOMETRY_RESIDUAL_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/bearing/bearing_model.h>
#include <calib/core/se2.h>
#include <calib/problems/bearing/bearing_observation_residual.h>
#include <ceres/autodiff_cost_function.h>
#include <ceres/jet.h>

#include <Eigen/Core>
#include <vector>

namespace calib {

namespace bearing_internal {

using Jet2 = ceres::Jet<double, 2>;

inline double Value(double x) { return x; }
template <int N>
double Value(const ceres::Jet<double, N>& x) {
  return x.a;
}

// A pose computed with Jet2 derivatives d/d(δ, ξ), carried over to the scalar of the caller by
// the chain rule (for double: the value alone).
inline Pose2d Lift(const Pose2<Jet2>& p, double /*delta*/, double /*xi*/) {
  return Pose2d(p(0).a, p(1).a, p(2).a);
}
template <int N>
Pose2<ceres::Jet<double, N>> Lift(const Pose2<Jet2>& p, const ceres::Jet<double, N>& delta,
                                  const ceres::Jet<double, N>& xi) {
  Pose2<ceres::Jet<double, N>> out;
  for (int i = 0; i < 3; ++i) {
    out(i).a = p(i).a;
    out(i).v = p(i).v[0] * delta.v + p(i).v[1] * xi.v;
  }
  return out;
}

}  // namespace bearing_internal

// Odometry pose-composition term between consecutive poses x0 (time t0) and x1 (time t1 > t0)
// of one run. In the scale gauge δR ≡ 1 eq. 2 reads, for nominal wheel travels r·Δα:
//   v = r(Δα_R + δ·Δα_L)/2,   ω = r·ξ(Δα_R − δ·Δα_L)        (δB = 1/(B·ξ)),
// and the encoder steps between t0 and t1, composed as constant-speed arcs, predict
//   Δ̂(δ, ξ) = IntegrateEncoders(t0 → t1; δR = 1, δL = δ, δB = 1/(B·ξ)).
// The residual compares it with the displacement between the two pose blocks:
//   e = Δ̂⁻¹ ∘ (x0⁻¹ ∘ x1)   (e_θ wrapped),   r = L·e,   LᵀL = Σ⁻¹,
// with Σ = K²·Σ₁ + floor the first-order covariance of Δ̂ when each encoder increment is read
// with variance K²/r·|Δα| (§8.1), Σ₁ its value for K = 1 (EncoderDisplacementCovariance).
// Parameter blocks: x0 (3), x1 (3), the calibration (5; only δ and ξ enter). The prediction
// depends on two parameters only, so it is differentiated with 2-component Jets and chained into
// the caller's Jets: integrating ~50 encoder steps per term costs little whatever the Jet size.
// `odometry` and `sqrt_information` are held by pointer and must outlive the cost function.
class BearingOdometryResidual {
 public:
  BearingOdometryResidual(const std::vector<EncoderSample>* odometry, double t0_s, double t1_s,
                          double wheel_radius_m, double wheelbase_m,
                          const Eigen::Matrix3d* sqrt_information)
      : odometry_(odometry),
        t0_s_(t0_s),
        t1_s_(t1_s),
        wheel_radius_m_(wheel_radius_m),
        wheelbase_m_(wheelbase_m),
        sqrt_information_(sqrt_information) {}

  template <typename T>
  bool operator()(const T* const world_T_robot0, const T* const world_T_robot1,
                  const T* const calibration, T* residual) const {
    using bearing_internal::Jet2;
    const Jet2 delta(bearing_internal::Value(calibration[kBearingDelta]), 0);
    const Jet2 xi(bearing_internal::Value(calibration[kBearingXi]), 1);
    const Pose2<T> predicted = bearing_internal::Lift(
        Predict(delta, xi), calibration[kBearingDelta], calibration[kBearingXi]);
    const Pose2<T> x0(world_T_robot0[0], world_T_robot0[1], world_T_robot0[2]);
    const Pose2<T> x1(world_T_robot1[0], world_T_robot1[1], world_T_robot1[2]);
    Pose2<T> error = Between(predicted, Between(x0, x1));
    error(2) = WrapAngle(error(2));
    Eigen::Map<Eigen::Matrix<T, 3, 1>> whitened(residual);
    whitened = sqrt_information_->cast<T>() * error;
    return true;
  }

  // Δ̂(δ, ξ) for any scalar.
  template <typename S>
  Pose2<S> Predict(const S& delta, const S& xi) const {
    return IntegrateEncoders(*odometry_, t0_s_, t1_s_, wheel_radius_m_, wheelbase_m_, S(1.0), delta,
                             S(1.0) / (xi * wheelbase_m_));
  }

  // The unwhitened error e.
  Eigen::Vector3d Error(const double* world_T_robot0, const double* world_T_robot1,
                        const double* calibration) const {
    const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
    BearingOdometryResidual unit(odometry_, t0_s_, t1_s_, wheel_radius_m_, wheelbase_m_, &identity);
    Eigen::Vector3d e;
    unit(world_T_robot0, world_T_robot1, calibration, e.data());
    return e;
  }

  static ceres::CostFunction* Create(const std::vector<EncoderSample>* odometry, double t0_s,
                                     double t1_s, double wheel_radius_m, double wheelbase_m,
                                     const Eigen::Matrix3d* sqrt_information) {
    return new ceres::AutoDiffCostFunction<BearingOdometryResidual, 3, 3, 3, kNumBearingParams>(
        new BearingOdometryResidual(odometry, t0_s, t1_s, wheel_radius_m, wheelbase_m,
                                    sqrt_information));
  }

 private:
  const std::vector<EncoderSample>* odometry_;
  double t0_s_;
  double t1_s_;
  double wheel_radius_m_;
  double wheelbase_m_;
  const Eigen::Matrix3d* sqrt_information_;
};

}  // namespace calib

#endif  // CALIB_PROBLEMS_BEARING_BEARING_ODOMETRY_RESIDUAL_H_
