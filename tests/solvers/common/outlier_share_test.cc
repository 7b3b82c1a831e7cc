#include <calib/solvers/common/outlier_share.h>
#include <gtest/gtest.h>

#include <random>

namespace calib {
namespace {

Eigen::MatrixXd Residuals(int n, double gross_share, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 1e-3), gross(0.0, 0.3);
  std::bernoulli_distribution is_gross(gross_share);
  Eigen::MatrixXd r(n, 3);
  for (int i = 0; i < n; ++i) {
    const bool g = is_gross(rng);
    for (int c = 0; c < 3; ++c) r(i, c) = g ? gross(rng) : noise(rng);
  }
  return r;
}

TEST(OutlierShareTest, GaussianNoiseHasNone) {
  EXPECT_LT(GrossOutlierShare(Residuals(5000, 0.0, 1)), 0.002);
}

TEST(OutlierShareTest, NoiseFreeResidualsHaveNone) {
  EXPECT_EQ(GrossOutlierShare(Eigen::MatrixXd::Constant(100, 3, 1e-16)), 0.0);
}

// Measured up to 70 % gross, where the median-based noise level is the outliers'.
TEST(OutlierShareTest, MeasuresTheGrossShare) {
  for (const double share : {0.05, 0.2, 0.45, 0.6, 0.7}) {
    EXPECT_NEAR(GrossOutlierShare(Residuals(5000, share, 2)), share, 0.03) << share;
  }
}

TEST(OutlierShareTest, NonFiniteIsGross) {
  Eigen::MatrixXd r = Residuals(100, 0.0, 3);
  r(7, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NEAR(GrossOutlierShare(r), 0.01, 1e-12);
}

}  // namespace
}  // namespace calib
