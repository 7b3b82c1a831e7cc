#ifndef CALIB_PROBLEMS_BEARING_BEARING_TIME_OFFSET_RESIDUAL_H_
#define CALIB_PROBLEMS_BEARING_BEARING_TIME_OFFSET_RESIDUAL_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/bearing/bearing_model.h>
#include <calib/core/se2.h>
#include <calib/problems/bearing/bearing_observation_residual.h>
#include <ceres/autodiff_cost_function.h>

#include <vector>

namespace calib {

// Bearing observation term with a clock offset τ (the contract's `time_offset`): the bearing
// stamped t was taken at t + τ on the odometry clock. The pose block x stays at the stamp t; the
// robot's pose when the bearing was taken is x advanced by the encoders over [t, t + τ]:
//   x_τ = x ⊕ Δ̂(t → t + τ; δR = 1, δL = δ, δB = 1/(B·ξ)),
//   r = wrap(β − β̂(x_τ; φ, ψ, η)) / σβ,
// which is BearingObservationResidual exactly at τ = 0 (Δ̂ over an empty window is the
// identity), so autodiff gives the sensitivity ∂r/∂τ at τ = 0 for the score test. Within an
// encoder step the wheels turn at that step's constant speed, and the robot stands still outside
// the run's samples.
// Parameter blocks: the pose (3), the calibration (5), τ (1). `odometry` and `inverse_sigma`
// are held by pointer and must outlive the cost function.
class BearingTimeOffsetResidual {
 public:
  BearingTimeOffsetResidual(double bearing_rad, double t_s,
                            const std::vector<EncoderSample>* odometry, double wheel_radius_m,
                            double wheelbase_m, const double* inverse_sigma)
      : bearing_rad_(bearing_rad),
        t_s_(t_s),
        odometry_(odometry),
        wheel_radius_m_(wheel_radius_m),
        wheelbase_m_(wheelbase_m),
        inverse_sigma_(inverse_sigma) {}

  template <typename T>
  bool operator()(const T* const world_T_robot, const T* const calibration,
                  const T* const time_offset, T* residual) const {
    const Pose2<T> pose(world_T_robot[0], world_T_robot[1], world_T_robot[2]);
    const T delta_b = T(1.0) / (calibration[kBearingXi] * wheelbase_m_);
    const Pose2<T> advance =
        IntegrateEncoders(*odometry_, T(t_s_), T(t_s_) + time_offset[0], wheel_radius_m_,
                          wheelbase_m_, T(1.0), calibration[kBearingDelta], delta_b);
    const T rho = T(0.5) / calibration[kBearingEta];
    const T predicted = BearingFromPose(Compose(pose, advance), calibration[kBearingPhi], rho,
                                        calibration[kBearingPsi]);
    residual[0] = WrapAngle(T(bearing_rad_) - predicted) * T(*inverse_sigma_);
    return true;
  }

  // The unwhitened error wrap(β − β̂).
  double Error(const double* world_T_robot, const double* calibration,
               const double* time_offset) const {
    const double one = 1.0;
    BearingTimeOffsetResidual unit(bearing_rad_, t_s_, odometry_, wheel_radius_m_, wheelbase_m_,
                                   &one);
    double e = 0.0;
    unit(world_T_robot, calibration, time_offset, &e);
    return e;
  }

  static ceres::CostFunction* Create(double bearing_rad, double t_s,
                                     const std::vector<EncoderSample>* odometry,
                                     double wheel_radius_m, double wheelbase_m,
                                     const double* inverse_sigma) {
    return new ceres::AutoDiffCostFunction<BearingTimeOffsetResidual, 1, 3, kNumBearingParams, 1>(
        new BearingTimeOffsetResidual(bearing_rad, t_s, odometry, wheel_radius_m, wheelbase_m,
                                      inverse_sigma));
  }

 private:
  double bearing_rad_;
  double t_s_;
  const std::vector<EncoderSample>* odometry_;
  double wheel_radius_m_;
  double wheelbase_m_;
  const double* inverse_sigma_;
};

}  // namespace calib

#endif  // CALIB_PROBLEMS_BEARING_BEARING_TIME_OFFSET_RESIDUAL_H_
