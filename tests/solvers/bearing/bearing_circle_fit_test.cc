#include <calib/core/bearing/bearing_model.h>
#include <calib/solvers/bearing/bearing_circle_fit.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace calib {
namespace {

void ExpectAngleNear(double a, double b, double tol) { EXPECT_NEAR(WrapAngle(a - b), 0.0, tol); }

void ExpectRelNear(double a, double b, double tol) {
  EXPECT_NEAR(a / b, 1.0, tol) << a << " vs " << b;
}

TEST(BearingCircleFitTest, UnevenSamplesBothSenses) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (double xi : {2.3, -0.7, 0.05, 9.0}) {
    const BearingCircle truth{xi, 0.3 / std::abs(xi), 2.5, -1.8};
    const double period = 2 * M_PI / std::abs(xi);
    std::vector<double> s, beta;
    for (int i = 0; i < 40; ++i) {
      s.push_back(1.0 + 1.3 * period * std::pow(unit(rng), 1.5));  // Denser at the start.
      beta.push_back(CircleBearing(truth, s.back()));
    }
    const StatusOr<BearingCircle> fit =
        FitBearingCircle(s, beta, 0.1 / (1.3 * period), 20.0 / (1.3 * period));
    ASSERT_TRUE(fit.ok()) << fit.message();
    ExpectRelNear(fit->xi_q_per_m, xi, 1e-10);
    for (double x : {0.0, 1.7, 5.0})
      ExpectAngleNear(CircleBearing(*fit, x), CircleBearing(truth, x), 1e-9);
  }
}

// Noise-free samples of a known circle: its covariance vanishes, its residual is zero.
TEST(BearingCircleFitTest, ExactCircleHasNoResidual) {
  const BearingCircle truth{1.1, 0.4, 0.7, 0.5};
  std::vector<double> s, beta;
  for (int i = 0; i < 50; ++i) {
    s.push_back(0.2 * i);
    beta.push_back(CircleBearing(truth, s.back()));
  }
  EXPECT_LT(CircleRmsResidual(truth, s, beta), 1e-12);
  EXPECT_LT(CircleCovariance(truth, s, beta).norm(), 1e-20);
  EXPECT_EQ(FitBearingCircle({0.0, 1.0}, {0.0, 0.1}, 0.1, 1.0).code(), StatusCode::kInvalidInput);
}

}  // namespace
}  // namespace calib
