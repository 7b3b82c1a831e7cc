// The interval-jitter likelihood's maximizations: the profile in θ and the joint scoring in
// (θ, σ_j²) end where the likelihood is highest, also when the jitter explains a noise variance
// entirely (that variance then sits on the floor).
#include <calib/solvers/timing/interval_jitter_likelihood.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <random>

namespace calib::jitter_internal {
namespace {

// N intervals with random time sensitivities g_s, g_e and errors drawn from
// N(0, diag(θ) + σ_j²·(g_s g_sᵀ + g_e g_eᵀ)). `only_y`: the sensitivities have a y part only.
JitterData Draw(int n, const Eigen::Vector3d& theta, double jitter_s, bool only_y, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  JitterData data;
  for (int k = 0; k < n; ++k) {
    Eigen::Vector3d gs(normal(rng), normal(rng), normal(rng));
    Eigen::Vector3d ge(normal(rng), normal(rng), normal(rng));
    if (only_y) gs = Eigen::Vector3d(0, gs(1), 0), ge = Eigen::Vector3d(0, ge(1), 0);
    const Eigen::Matrix3d g = gs * gs.transpose() + ge * ge.transpose();
    const Eigen::Matrix3d sigma = Eigen::Matrix3d(theta.asDiagonal()) + jitter_s * jitter_s * g;
    const Eigen::Vector3d e =
        sigma.llt().matrixL() * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    const double error[3] = {e(0), e(1), e(2)};
    const double packed[6] = {g(0, 0), g(0, 1), g(0, 2), g(1, 1), g(1, 2), g(2, 2)};
    data.Add(error, packed);
  }
  return data;
}

// θ is the profile's maximum: no variance can move (by 1 % up or down) to a higher value.
void ExpectProfileMaximum(const JitterData& data, double jitter_s, const Eigen::Vector3d& theta,
                          double value) {
  EXPECT_NEAR(LogLikelihood(data, theta, jitter_s * jitter_s), value, 1e-9 * std::abs(value));
  for (int i = 0; i < 3; ++i) {
    for (double factor : {0.99, 1.01}) {
      Eigen::Vector3d moved = theta;
      moved(i) = std::max(theta(i) * factor, kMinVariance);
      EXPECT_LE(LogLikelihood(data, moved, jitter_s * jitter_s), value + 1e-9) << i << factor;
    }
  }
}

TEST(IntervalJitterLikelihoodTest, TheProfileEndsAtItsMaximum) {
  const Eigen::Vector3d truth(1e-6, 4e-6, 1e-5);
  const JitterData data = Draw(2000, truth, 0.01, false, 1);
  for (double jitter_s : {0.0, 0.003, 0.01, 0.03}) {
    Eigen::Vector3d theta = truth * 50.0;  // Far from it.
    const double value = ProfileLogLikelihood(data, jitter_s, true, &theta);
    ExpectProfileMaximum(data, jitter_s, theta, value);
  }
}

// Without jitter the profile is in closed form (the mean squared errors); the scoring at a jitter
// too small to matter ends there too.
TEST(IntervalJitterLikelihoodTest, WithoutJitterTheProfileIsTheMeanSquare) {
  const Eigen::Vector3d truth(1e-6, 4e-6, 1e-5);
  const JitterData data = Draw(2000, truth, 0.01, false, 3);
  Eigen::Vector3d closed = truth * 50.0, scored = truth * 50.0;
  const double value = ProfileLogLikelihood(data, 0.0, true, &closed);
  const double scored_value = ProfileLogLikelihood(data, 1e-12, true, &scored);
  for (int i = 0; i < 3; ++i) {
    double sum = 0.0;
    for (const double e : data.error[i]) sum += e * e;
    EXPECT_DOUBLE_EQ(closed(i), sum / static_cast<double>(data.size()));
    EXPECT_NEAR(scored(i), closed(i), 1e-8 * closed(i));
  }
  EXPECT_NEAR(value, scored_value, 1e-9 * std::abs(value));
  EXPECT_EQ(value, LogLikelihood(data, closed, 0.0));
}

// A jitter that explains the y errors entirely drives θ_y to the floor (in a few passes rather
// than one tenth per pass); the other variances still reach their maximum.
TEST(IntervalJitterLikelihoodTest, AVarianceTheJitterExplainsFallsToTheFloor) {
  const Eigen::Vector3d truth(1e-6, 0.0, 1e-5);
  const JitterData data = Draw(2000, truth, 0.01, true, 2);
  Eigen::Vector3d theta(1e-6, 1e-6, 1e-5);
  const double value = ProfileLogLikelihood(data, 0.02, true, &theta);  // Twice the jitter.
  EXPECT_EQ(kMinVariance, theta(1));
  EXPECT_NEAR(truth(0), theta(0), 0.1 * truth(0));
  EXPECT_NEAR(truth(2), theta(2), 0.1 * truth(2));
  ExpectProfileMaximum(data, 0.02, theta, value);
}

// The joint scoring ends at the profile's maximum along σ_j: nearby σ_j profile lower.
TEST(IntervalJitterLikelihoodTest, TheJointScoringEndsAtTheProfilesMaximum) {
  const Eigen::Vector3d truth(1e-6, 4e-6, 1e-5);
  const JitterData data = Draw(3000, truth, 0.01, false, 3);
  Eigen::Vector3d theta = truth;
  double jitter_s = 0.005;
  ASSERT_TRUE(JointMaximum(data, 0.001, 0.1, &theta, &jitter_s));
  EXPECT_NEAR(0.01, jitter_s, 0.001);
  Eigen::Vector3d profiled = theta;
  const double best = ProfileLogLikelihood(data, jitter_s, true, &profiled);
  EXPECT_LT(((profiled - theta).cwiseQuotient(theta)).cwiseAbs().maxCoeff(), 1e-6);
  for (double factor : {0.99, 1.01}) {
    Eigen::Vector3d other = theta;
    EXPECT_LT(ProfileLogLikelihood(data, jitter_s * factor, true, &other), best);
  }
}

// Its observed information gives σ_j²'s variance: the inverse of the profile's curvature in σ_j²
// (by central differences of a small step).
TEST(IntervalJitterLikelihoodTest, TheJointInformationIsTheProfilesCurvature) {
  const Eigen::Vector3d truth(1e-6, 4e-6, 1e-5);
  const JitterData data = Draw(3000, truth, 0.01, false, 4);
  Eigen::Vector3d theta = truth;
  double jitter_s = 0.005;
  Eigen::Matrix4d information = Eigen::Matrix4d::Constant(std::nan(""));
  ASSERT_TRUE(JointMaximum(data, 0.001, 0.1, &theta, &jitter_s, &information));
  ASSERT_TRUE(information.allFinite());
  const double variance = information.inverse()(3, 3);
  ASSERT_GT(variance, 0.0);
  const double square = jitter_s * jitter_s, h = 1e-3 * square;
  const auto profile = [&](double s) {
    Eigen::Vector3d warm = theta;
    return ProfileLogLikelihood(data, std::sqrt(s), true, &warm, 1e-13);
  };
  const double curvature =
      (profile(square + h) - 2.0 * profile(square) + profile(square - h)) / (h * h);
  EXPECT_NEAR(variance, -1.0 / curvature, 1e-3 * variance);
}

// The moments' start lies near the maximum where the jitter is clear, and is withheld (0) where
// there is none, nearly always at 3 standard errors.
TEST(IntervalJitterLikelihoodTest, TheMomentsStartNearTheJitterOnlyWhenThereIsOne) {
  const Eigen::Vector3d truth(1e-6, 4e-6, 1e-5);
  for (unsigned seed = 5; seed < 10; ++seed) {
    const double start = MomentJitter(Draw(3000, truth, 0.01, false, seed));
    EXPECT_GT(start, 0.01 / 1.2) << seed;  // Well inside the search's factor of 3.
    EXPECT_LT(start, 0.01 * 1.2) << seed;
  }
  int withheld = 0;
  for (unsigned seed = 20; seed < 40; ++seed)
    withheld += MomentJitter(Draw(3000, truth, 0.0, false, seed)) == 0.0;
  EXPECT_GE(withheld, 19);
}

}  // namespace
}  // namespace calib::jitter_internal
