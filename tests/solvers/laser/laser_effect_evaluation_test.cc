// The effect fits' evaluation at γ = 0 (the base residual's closed-form columns; the effects'
// in closed form on constant-speed intervals, differentiated in γ alone on stepped ones) against
// automatic derivatives in all fifteen parameters.
#include <calib/core/laser/laser_simulator.h>
#include <calib/problems/laser/laser_effect_residual.h>
#include <calib/solvers/laser/laser_effect_fit.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace calib {
namespace {

// Every residual and column of the evaluation at γ = 0 against 15-wide automatic derivatives.
void ExpectDerivativesInAllParameters(const LaserLog& log, double change_time_s) {
  const Eigen::Matrix3d sqrt_information = Eigen::Vector3d(1e3, 2e3, 5e2).asDiagonal();
  const LaserEffectData data(log.intervals, sqrt_information, LaserRefinementOptions());
  LaserCalibration calibration;
  calibration.odometry = OdometryParams{0.021, 0.0205, 0.09};
  calibration.base_T_sensor = Pose2d(0.01, -0.02, 0.7);
  for (BoundarySpeedModel boundary :
       {BoundarySpeedModel::kPiecewiseConstant, BoundarySpeedModel::kSmooth}) {
    LaserEffectModel model;
    model.boundary = boundary;
    model.change_time_s = change_time_s;
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
        EXPECT_NEAR(evaluation.residual(k, i), r[i], 1e-12 * (1.0 + std::abs(r[i])))
            << "interval " << k;
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

TEST(LaserEffectEvaluationTest, AtZeroEffectsMatchesDerivativesInAllParameters) {
  LaserSimOptions sim;
  sim.num_intervals = 400;
  sim.seed = 11;
  for (int steps : {3, 0}) {  // Logs with encoder sub-steps, and constant-speed intervals.
    sim.record_steps = steps;
    const LaserLog log = SimulateLaserLog(sim);
    SCOPED_TRACE(steps);
    // A radius change at an interval's start, and inside one (γ = 0 must not mind either).
    const LaserInterval& inside = log.intervals[200];
    for (double change : {log.intervals[150].start_s, inside.start_s + inside.duration_s / 3.0}) {
      ExpectDerivativesInAllParameters(log, change);
    }
  }
}

}  // namespace
}  // namespace calib
