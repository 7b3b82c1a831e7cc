#include <calib/solvers/common/robust_covariance.h>
#include <calib/solvers/common/robust_loss.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>
#include <vector>

namespace calib {
namespace {

constexpr int kP = 3;
using Matrix = Eigen::Matrix<double, kP, kP>;
using Jacobian = Eigen::Matrix<double, 1, kP>;

// A small linear problem: random Jacobians, residuals of one magnitude c with random signs (all
// blocks alike, where the scalar correction is exact).
struct SmallProblem {
  std::vector<Jacobian> j;
  std::vector<double> r;
};

SmallProblem MakeProblem(int n, double c, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  SmallProblem p;
  for (int i = 0; i < n; ++i) {
    Jacobian j;
    for (int k = 0; k < kP; ++k) j(k) = uniform(rng);
    p.j.push_back(j);
    p.r.push_back(uniform(rng) < 0.0 ? -c : c);
  }
  return p;
}

// The weighted Gauss–Newton covariance (Σ ρ'·JᵀJ)⁻¹, as ceres::Covariance returns it with the
// loss applied (Cauchy, Huber).
Matrix WeightedCovariance(const SmallProblem& p, const ceres::LossFunction* loss) {
  Matrix information = Matrix::Zero();
  for (size_t i = 0; i < p.j.size(); ++i) {
    information += EvaluateLoss(loss, p.r[i] * p.r[i]).rho1 * p.j[i].transpose() * p.j[i];
  }
  return information.inverse();
}

TEST(RobustCovarianceTest, KappaTimesWeightedCovarianceIsTheSandwich) {
  // |r| = 1.2, inside the Cauchy loss's region of positive curvature (scale 1.5). (Beyond its
  // corner a 1-D Huber residual has none: ρ' + 2ρ''s = 0.)
  const SmallProblem p = MakeProblem(40, 1.2, 3);
  for (RobustLoss kind : {RobustLoss::kCauchy, RobustLoss::kNone}) {
    const std::unique_ptr<ceres::LossFunction> loss = MakeLossFunction(kind, 1.5);
    LossCorrectionSums kappa_sums;
    SandwichSums<kP> sandwich_sums;
    for (size_t i = 0; i < p.j.size(); ++i) {
      const double s = p.r[i] * p.r[i];
      kappa_sums.Add(s, loss.get());
      sandwich_sums.Add(p.j[i], Eigen::Matrix<double, 1, 1>(p.r[i]), EvaluateLoss(loss.get(), s));
    }
    const double n = static_cast<double>(p.j.size());
    const StatusOr<double> kappa = LossCorrection(kappa_sums, n, n - kP);
    const auto sandwich = SandwichCovariance(sandwich_sums, n, n - kP);
    ASSERT_TRUE(kappa.ok() && sandwich.ok()) << RobustLossName(kind);
    EXPECT_EQ(sandwich->kappa, 1.0);
    const Matrix scaled = *kappa * WeightedCovariance(p, loss.get());
    EXPECT_LT((scaled - sandwich->covariance).norm(), 1e-12 * sandwich->covariance.norm())
        << RobustLossName(kind);
  }
}

// For the squared loss κ is σ̂² = Σr²/(n − p), whatever the residuals.
TEST(RobustCovarianceTest, SquaredLossKappaIsTheResidualVariance) {
  std::mt19937 rng(5);
  std::normal_distribution<double> normal(0.0, 0.3);
  LossCorrectionSums sums;
  double sum_sq = 0.0;
  const int blocks = 30, dimension = 3;
  for (int i = 0; i < blocks; ++i) {
    const Eigen::Vector3d r(normal(rng), normal(rng), normal(rng));
    sums.Add(r.squaredNorm(), nullptr, dimension);
    sum_sq += r.squaredNorm();
  }
  const double n = blocks * dimension;
  const StatusOr<double> kappa = LossCorrection(sums, n, n - 6);
  ASSERT_TRUE(kappa.ok());
  EXPECT_NEAR(*kappa, sum_sq / (n - 6), 1e-14);
}

TEST(RobustCovarianceTest, NoRedundancyIsNotObservable) {
  LossCorrectionSums sums;
  sums.Add(1.0, nullptr);
  EXPECT_EQ(LossCorrection(sums, 1.0, 0.0).code(), StatusCode::kNotObservable);
  EXPECT_EQ(LossCorrection(LossCorrectionSums{}, 1.0, 1.0).code(), StatusCode::kNotObservable);
  SandwichSums<2> singular;
  EXPECT_EQ(SandwichCovariance(singular, 4.0, 2.0).code(), StatusCode::kNotObservable);
}

// Without a loss: the likelihood-ratio scale is mean(s/d) and Newton equals Gauss–Newton.
TEST(RobustCovarianceTest, LikelihoodRatioScaleAndCurvatureRatioOfTheSquaredLoss) {
  LossCorrectionSums sums;
  sums.Add(3.0, nullptr, 3);
  sums.Add(6.0, nullptr, 3);
  EXPECT_DOUBLE_EQ(*LikelihoodRatioScale(sums), 1.5);
  EXPECT_DOUBLE_EQ(*CurvatureRatio(sums), 1.0);
  EXPECT_FALSE(LikelihoodRatioScale(LossCorrectionSums{}).has_value());
  EXPECT_FALSE(CurvatureRatio(LossCorrectionSums{}).has_value());
}

// The dynamic-size sums give what the fixed-size ones give.
TEST(RobustCovarianceTest, DynamicSandwichMatchesFixed) {
  SandwichSums<2> fixed;
  SandwichSums<Eigen::Dynamic> dynamic(2);
  const LossDerivatives rho{0.8, -0.1};
  const Eigen::Matrix2d j = (Eigen::Matrix2d() << 1.0, 0.5, -0.2, 2.0).finished();
  const Eigen::Vector2d r(0.3, -0.7);
  fixed.Add(j, r, rho);
  dynamic.Add(Eigen::MatrixXd(j), Eigen::VectorXd(r), rho);
  EXPECT_LT((dynamic.bread - fixed.bread).norm(), 1e-15);
  EXPECT_LT((dynamic.meat - fixed.meat).norm(), 1e-15);
  const Eigen::VectorXd g = SandwichSums<Eigen::Dynamic>(2).AddBread(j, r, rho);
  EXPECT_LT((g - j.transpose() * r).norm(), 1e-15);
  const auto a = SandwichCovariance(fixed, 4.0, 2.0);
  const auto b = SandwichCovariance(dynamic.bread, dynamic.meat, 4.0, 2.0);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_LT((a->covariance - b->covariance).norm(), 1e-12);
}

// The dominating covariance holds both: every combination's variance is at least the larger of
// its two, it is the model where the sandwich is smaller in every direction, and its largest ratio
// is the largest generalized eigenvalue.
TEST(RobustCovarianceTest, DominatingCovarianceHoldsBoth) {
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  const auto random_spd = [&](int n) {
    Eigen::MatrixXd a(n, n);
    for (int i = 0; i < n * n; ++i) a(i) = normal(rng);
    return Eigen::MatrixXd(a * a.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n));
  };
  const Eigen::MatrixXd model = random_spd(5), sandwich = random_spd(5);
  const DominatingCovarianceResult both = DominatingCovariance(model, sandwich);
  double largest = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::VectorXd g(5);
    for (int i = 0; i < 5; ++i) g(i) = normal(rng);
    const double v = g.dot(both.covariance * g);
    EXPECT_GE(v, (1.0 - 1e-9) * std::max(g.dot(model * g), g.dot(sandwich * g)));
    largest = std::max(largest, g.dot(sandwich * g) / g.dot(model * g));
  }
  EXPECT_GE(both.largest_ratio, largest);
  const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> eigen(sandwich, model);
  EXPECT_NEAR(both.largest_ratio, eigen.eigenvalues().maxCoeff(), 1e-9 * both.largest_ratio);

  const DominatingCovarianceResult model_only = DominatingCovariance(model, 0.5 * model);
  EXPECT_LT((model_only.covariance - model).cwiseAbs().maxCoeff(), 1e-9 * model.norm());
  EXPECT_DOUBLE_EQ(model_only.largest_ratio, 1.0);
  // A model that is not positive definite is returned as it is.
  const Eigen::MatrixXd singular = Eigen::MatrixXd::Zero(5, 5);
  EXPECT_EQ(DominatingCovariance(singular, sandwich).covariance, singular);
  // An indefinite second one (a lag-1 model with an estimated correlation) is floored by the first.
  Eigen::MatrixXd indefinite = sandwich;
  indefinite(0, 0) = -indefinite(0, 0);
  const DominatingCovarianceResult floored = DominatingCovariance(0.01 * model, indefinite);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> floored_eigen(floored.covariance);
  EXPECT_GT(floored_eigen.eigenvalues().minCoeff(), 0.0);
  Eigen::VectorXd e0 = Eigen::VectorXd::Zero(5);
  e0(0) = 1.0;
  EXPECT_GE(e0.dot(floored.covariance * e0), (1.0 - 1e-9) * 0.01 * model(0, 0));
}

}  // namespace
}  // namespace calib
