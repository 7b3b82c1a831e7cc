#include <calib/solvers/common/robust_covariance.h>
#include <calib/solvers/common/robust_loss.h>
#include <gtest/gtest.h>

#include <memory>

namespace calib {
namespace {

TEST(RobustLossTest, NamesRoundTrip) {
  for (RobustLoss loss :
       {RobustLoss::kCauchy, RobustLoss::kHuber, RobustLoss::kNone, RobustLoss::kTukey}) {
    const StatusOr<RobustLoss> parsed = ParseRobustLoss(RobustLossName(loss));
    ASSERT_TRUE(parsed.ok());
    EXPECT_EQ(*parsed, loss);
  }
  const StatusOr<RobustLoss> unknown = ParseRobustLoss("tukey2");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.message().find("expected cauchy, huber, tukey or none"), std::string::npos);
}

// ρ' and ρ'' against central differences of ρ, inside the scale and beyond it.
TEST(RobustLossTest, TukeyDerivativesMatchDifferences) {
  const std::unique_ptr<ceres::LossFunction> loss = MakeLossFunction(RobustLoss::kTukey, 6.0);
  const double h = 1e-5;
  for (double s : {0.0, 0.5, 3.0, 20.0, 35.0, 40.0, 1e6}) {
    double rho[3], plus[3], minus[3];
    loss->Evaluate(s, rho);
    loss->Evaluate(s + h, plus);
    loss->Evaluate(std::max(s - h, 0.0), minus);
    const double step = s + h - std::max(s - h, 0.0);
    EXPECT_NEAR(rho[1], (plus[0] - minus[0]) / step, 1e-6) << s;
    EXPECT_NEAR(rho[2], (plus[1] - minus[1]) / step, 1e-6) << s;
  }
}

// Like the other losses it weighs a zero residual fully (ceres::TukeyLoss weighs it ½), and a
// residual beyond its scale not at all, with ρ continuous there.
TEST(RobustLossTest, TukeyWeighsFullyAtZeroAndNotBeyondItsScale) {
  const std::unique_ptr<ceres::LossFunction> loss = MakeLossFunction(RobustLoss::kTukey, 6.0);
  EXPECT_DOUBLE_EQ(EvaluateLoss(loss.get(), 0.0).rho1, 1.0);
  EXPECT_NEAR(EvaluateLoss(loss.get(), 3.0).rho1, (1.0 - 3.0 / 36.0) * (1.0 - 3.0 / 36.0), 1e-15);
  EXPECT_EQ(EvaluateLoss(loss.get(), 36.0).rho1, 0.0);
  EXPECT_EQ(EvaluateLoss(loss.get(), 1e300).rho1, 0.0);
  double below[3], beyond[3];
  loss->Evaluate(36.0 - 1e-9, below);
  loss->Evaluate(1e9, beyond);
  EXPECT_NEAR(below[0], beyond[0], 1e-9);
  EXPECT_DOUBLE_EQ(beyond[0], 12.0);  // a²/3.
}

}  // namespace
}  // namespace calib
