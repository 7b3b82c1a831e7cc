// The effect fits' evaluation at γ = 0, which takes the base residual's closed-form columns and
// differentiates in γ alone, against automatic derivatives in all fifteen parameters.
#include <calib/core/laser/laser_simulator.h>
#include <calib/problems/laser/laser_effect_residual.h>
#include <calib/solvers/laser/laser_effect_fit.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace calib {
namespace {

TEST(LaserEffectEvaluationTest, AtZeroEffectsMatchesDerivativesInAllParameters) {
  LaserSimOptions sim;
  sim.num_intervals = 400;
  sim.seed = 11;
  sim.record_steps = 3;  // The stepped model, as logs with encoder sub-steps.
  const LaserLog log = SimulateLaserLog(sim);
  const Eigen::Matrix3d sqrt_information = Eigen::Vector3d(1e3, 2e3, 5e2).asDiagonal();
  const LaserEffectData data(log.intervals, sqrt_information, LaserRefinementOptions());
  LaserCalibration calibration;
  calibration.odometry = OdometryParams{0.021, 0.0205, 0.09};
  calibration.base_T_sensor = Pose2d(0.01, -0.02, 0.7);
  for (BoundarySpeedModel boundary :
       {BoundarySpeedModel::kPiecewiseConstant, BoundarySpeedModel::kSmooth}) {
    LaserEffectModel model;
    model.boundary = boundary;
    model.change_time_s = log.intervals[150].start_s;  // Inside: γ = 0 must not mind.
    const LaserEffectEvaluation evaluation = EvaluateLaserEffects(data, model, calibration);
    const std::vector<LaserEffectContext> contexts = data.Contexts(model);
    const double odometry[3] = {0.021, 0.0205, 0.09};
    const double mounting[3] = {0.01, -0.02, 0.7};
    const double* parameters[3] = {odometry, mounting, model.gamma.data()};
    for (size_t k = 0; k < contexts.size(); ++k) {
      LaserEffectResidual functor(contexts[k], &data.sqrt_information(k));
      const ceres::AutoDiffCostFunction<LaserEffectResidual, 3, 3, 3, kNumLaserEffectParams> cost(
          &functor, ceres::DO_NOT_TAKE_OWNERSHIP);
      double r[3];
      double j[3][3 * kNumLaserEffectParams];
      std::fill(&r[0], &r[3], std::numeric_limits<double>::quiet_NaN());
      double* jacobians[3] = {j[0], j[1], j[2]};
      ASSERT_TRUE(cost.Evaluate(parameters, r, jacobians));
      const int widths[3] = {3, 3, kNumLaserEffectParams};
      for (int i = 0; i < 3; ++i) {
        EXPECT_EQ(evaluation.residual(k, i), r[i]) << "interval " << k;
        int column = 0;
        for (int b = 0; b < 3; ++b) {
          for (int c = 0; c < widths[b]; ++c, ++column) {
            const double expected = j[b][i * widths[b] + c];
            EXPECT_NEAR(evaluation.jacobian(3 * k + i, column), expected,
                        1e-12 * (1.0 + std::abs(expected)))
                << "interval " << k << " row " << i << " column " << column;
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace calib
