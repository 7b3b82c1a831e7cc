#include <calib/solvers/common/solver_options.h>
#include <gtest/gtest.h>

namespace calib {
namespace {

// The presets keep each refinement's own numbers (moving them would move the results).
TEST(SolverOptionsTest, PresetsKeepTheRefinementsTolerances) {
  const ceres::Solver::Options laser = MakeSolverOptions(LaserRefinementSettings(10000, 100, 2));
  EXPECT_EQ(laser.linear_solver_type, ceres::DENSE_NORMAL_CHOLESKY);
  EXPECT_EQ(laser.trust_region_strategy_type, ceres::LEVENBERG_MARQUARDT);
  EXPECT_EQ(laser.max_num_iterations, 100);
  EXPECT_EQ(laser.num_threads, 2);
  EXPECT_DOUBLE_EQ(laser.function_tolerance, 0.005 / 10000);
  EXPECT_EQ(MakeSolverOptions(LaserRefinementSettings(10, 100, 2)).function_tolerance, 1e-6);
  EXPECT_EQ(laser.gradient_tolerance, 1e-12);
  EXPECT_EQ(laser.parameter_tolerance, 1e-10);
  EXPECT_EQ(laser.initial_trust_region_radius,
            ceres::Solver::Options().initial_trust_region_radius);
  EXPECT_EQ(laser.logging_type, ceres::SILENT);

  const ceres::Solver::Options bearing = MakeSolverOptions(BearingAdjustmentSettings(200, 1, 1e10));
  EXPECT_EQ(bearing.linear_solver_type, ceres::SPARSE_NORMAL_CHOLESKY);
  EXPECT_EQ(bearing.max_num_iterations, 200);
  EXPECT_EQ(bearing.initial_trust_region_radius, 1e10);
  EXPECT_EQ(bearing.max_trust_region_radius, 1e16);
  EXPECT_EQ(bearing.function_tolerance, 1e-10);
  EXPECT_EQ(bearing.gradient_tolerance, 1e-14);
  EXPECT_EQ(bearing.parameter_tolerance, 1e-12);
}

TEST(SolverOptionsTest, CovarianceAppliesTheLoss) {
  const ceres::Covariance::Options options = MakeCovarianceOptions(3);
  EXPECT_EQ(options.num_threads, 3);
  EXPECT_EQ(options.algorithm_type, ceres::SPARSE_QR);
  EXPECT_TRUE(options.apply_loss_function);
}

TEST(SolverOptionsTest, ConvergenceIsReadFromTheTermination) {
  ceres::Solver::Summary summary;
  summary.termination_type = ceres::CONVERGENCE;
  EXPECT_TRUE(Converged(summary));
  summary.termination_type = ceres::NO_CONVERGENCE;
  EXPECT_FALSE(Converged(summary));
  EXPECT_NE(NotConvergedText("the fit", summary).find("the fit stopped after"), std::string::npos);
}

}  // namespace
}  // namespace calib
