// The score tests of solvers/stats/score_test.h: χ² and sup-χ² tails, the one-step estimate in a
// linear model, and a tester that owns its data.
#include <calib/solvers/stats/score_test.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

namespace calib {
namespace {

TEST(ScoreStatisticsTest, ChiSquareTailsMatchTables) {
  EXPECT_NEAR(ChiSquareSurvival(3.841459, 1), 0.05, 1e-6);
  EXPECT_NEAR(ChiSquareSurvival(5.991465, 2), 0.05, 1e-6);
  EXPECT_NEAR(ChiSquareSurvival(11.0705, 5), 0.05, 1e-5);
  EXPECT_NEAR(ChiSquareSurvival(43.773, 30), 0.05, 1e-4);
  EXPECT_NEAR(ChiSquareSurvival(10.828, 1), 0.001, 1e-6);
  EXPECT_EQ(ChiSquareSurvival(0.0, 3), 1.0);
}

TEST(ScoreStatisticsTest, SupTailMatchesAndrewsCriticalValues) {
  // Andrews (1993), Table 1, 5 % critical values for π0 = 0.15 (p = 1, 2) and π0 = 0.05.
  EXPECT_NEAR(SupChiSquareSurvival(8.85, 1, 0.15), 0.05, 0.006);
  EXPECT_NEAR(SupChiSquareSurvival(11.79, 2, 0.15), 0.05, 0.006);
  EXPECT_NEAR(SupChiSquareSurvival(9.84, 1, 0.05), 0.05, 0.006);
  // Always at least the single test's tail.
  EXPECT_GE(SupChiSquareSurvival(20.0, 2, 0.05), ChiSquareSurvival(20.0, 2));
}

// In a linear Gaussian model the score test with least squares is exact: the one-step
// estimate equals the full regression's coefficient, the concealment equals the R² of the
// candidate on the nuisance regressors.
TEST(ScoreStatisticsTest, OneStepIsTheRegressionCoefficientInALinearModel) {
  std::mt19937 rng(11);
  std::normal_distribution<double> normal(0.0, 1.0);
  const int n = 400;
  Eigen::MatrixXd x(n, 2);
  Eigen::VectorXd z(n), y(n);
  for (int k = 0; k < n; ++k) {
    x(k, 0) = 1.0;
    x(k, 1) = normal(rng);
    z(k) = 0.6 * x(k, 1) + 0.8 * normal(rng);  // Partly collinear with the nuisance.
    y(k) = 1.0 + 2.0 * x(k, 1) + 0.3 * z(k) + normal(rng);
  }
  // Nuisance-only fit, residual r = y − Xβ̂, J = −X, S = −z (one-dimensional residuals).
  const Eigen::VectorXd beta = x.colPivHouseholderQr().solve(y);
  RobustFitBlocks blocks;
  blocks.residual = y - x * beta;
  blocks.jacobian = -x;
  blocks.rho1 = Eigen::VectorXd::Ones(n);
  blocks.rho2 = Eigen::VectorXd::Zero(n);
  const ScoreTester tester(blocks, 0);
  ASSERT_TRUE(tester.ok());
  const ScoreTestResult result = tester.Test(-z);
  Eigen::MatrixXd xz(n, 3);
  xz << x, z;
  const Eigen::VectorXd full = xz.colPivHouseholderQr().solve(y);
  EXPECT_NEAR(result.gamma(0), full(2), 1e-10);
  EXPECT_NEAR(result.absorbed(1), beta(1) - full(1), 1e-10);  // θ̂ without γ − θ̂ with γ.
  const Eigen::VectorXd z_fit = x * x.colPivHouseholderQr().solve(z);
  const double r2 = 1.0 - (z - z_fit).squaredNorm() / z.squaredNorm();
  EXPECT_NEAR(result.concealment, r2, 1e-10);
  EXPECT_TRUE(result.identifiable);
  // A candidate that is a nuisance column is confounded.
  EXPECT_FALSE(tester.Test(-x.col(1)).identifiable);
}

// The tester keeps its own copy of the fit's blocks: built from a temporary, it still tests.
TEST(ScoreStatisticsTest, TesterOwnsItsBlocks) {
  const auto make_tester = []() {
    RobustFitBlocks blocks;
    blocks.residual = Eigen::VectorXd::LinSpaced(50, -1.0, 1.0);
    blocks.jacobian = Eigen::MatrixXd::Ones(50, 1);
    blocks.rho1 = Eigen::VectorXd::Ones(50);
    blocks.rho2 = Eigen::VectorXd::Zero(50);
    return ScoreTester(blocks, 0);  // `blocks` ends here.
  };
  const ScoreTester tester = make_tester();
  ASSERT_TRUE(tester.ok());
  EXPECT_EQ(tester.blocks().size(), 50u);
  // The residual is exactly linear in k: a slope candidate is significant.
  const ScoreTestResult result = tester.Test(-Eigen::VectorXd::LinSpaced(50, 0.0, 1.0));
  EXPECT_TRUE(result.identifiable);
  EXPECT_GT(result.statistic, 10.0);
}

}  // namespace
}  // namespace calib
