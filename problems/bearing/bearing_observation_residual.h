#ifndef CALIB_PROBLEMS_BEARING_BEARING_OBSERVATION_RESIDUAL_H_
#define CALIB_PROBLEMS_BEARING_BEARING_OBSERVATION_RESIDUAL_H_

#include <calib/core/bearing/bearing_model.h>
#include <calib/core/bearing/bearing_params.h>
#include <calib/core/se2.h>
#include <ceres/autodiff_cost_function.h>

namespace calib {

// Bearing observation term (eq. 6 as a measurement model). With the robot pose x = (x, y, θ) at
// the bearing's time (the landmark is the world origin) and the calibration c = (φ, ψ, η, δ, ξ):
//   sensor = x ⊕ (ρ cos φ, ρ sin φ, φ + ψ),   ρ = 1/(2η)   (δR ≡ 1: distances in units of δR),
//   β̂ = atan2(−sensor_y, −sensor_x) − sensor_θ,
//   r = wrap(β − β̂) / σβ.
// Parameter blocks: the pose (3) and the calibration (5). `inverse_sigma` (1/σβ) is held by
// pointer so that a re-estimated noise level applies without rebuilding the problem; it must
// outlive the cost function.
class BearingObservationResidual {
 public:
  BearingObservationResidual(double bearing_rad, const double* inverse_sigma)
      : bearing_rad_(bearing_rad), inverse_sigma_(inverse_sigma) {}

  template <typename T>
  bool operator()(const T* const world_T_robot, const T* const calibration, T* residual) const {
    const T rho = T(0.5) / calibration[kBearingEta];
    const Pose2<T> pose(world_T_robot[0], world_T_robot[1], world_T_robot[2]);
    const T predicted =
        BearingFromPose(pose, calibration[kBearingPhi], rho, calibration[kBearingPsi]);
    residual[0] = WrapAngle(T(bearing_rad_) - predicted) * T(*inverse_sigma_);
    return true;
  }

  // The unwhitened error wrap(β − β̂).
  static double Error(double bearing_rad, const double* world_T_robot, const double* calibration) {
    const double one = 1.0;
    double e = 0.0;
    BearingObservationResidual(bearing_rad, &one)(world_T_robot, calibration, &e);
    return e;
  }

  static ceres::CostFunction* Create(double bearing_rad, const double* inverse_sigma) {
    return new ceres::AutoDiffCostFunction<BearingObservationResidual, 1, 3, kNumBearingParams>(
        new BearingObservationResidual(bearing_rad, inverse_sigma));
  }

 private:
  double bearing_rad_;
  const double* inverse_sigma_;
};

}  // namespace calib

#endif  // CALIB_PROBLEMS_BEARING_BEARING_OBSERVATION_RESIDUAL_H_
