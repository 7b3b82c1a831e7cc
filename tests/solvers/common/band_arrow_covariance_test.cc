#include <calib/core/se2.h>
#include <calib/problems/positive_manifold.h>
#include <calib/solvers/common/band_arrow_covariance.h>
#include <calib/solvers/common/band_arrow_solver.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <memory>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include "tests/solvers/common/band_arrow_test_options.h"

namespace calib {
namespace {

// A point p_i ∈ R² in a chain: steps p_{i+1} − p_i = s·u_i (u known, s a positive scale) and
// bearings atan2(p_i) = β_i + c (a global offset c) under a Cauchy loss, the first point's x
// held by a subset manifold: block latents of two (one of them with a manifold), two globals.
struct StepTerm {
  StepTerm(const Eigen::Vector2d& u, double sigma) : u(u), sigma(sigma) {}
  template <typename T>
  bool operator()(const T* a, const T* b, const T* scale, T* r) const {
    for (int k = 0; k < 2; ++k) r[k] = (b[k] - a[k] - scale[0] * T(u(k))) / T(sigma);
    return true;
  }
  Eigen::Vector2d u;
  double sigma;
};

struct BearingTerm {
  explicit BearingTerm(double beta) : beta(beta) {}
  template <typename T>
  bool operator()(const T* p, const T* offset, T* r) const {
    using std::atan2;
    r[0] = WrapAngle(atan2(p[1], p[0]) - T(beta) - offset[0]) / T(0.01);
    return true;
  }
  double beta;
};

struct Chain {
  std::vector<Eigen::Vector2d> p;
  double scale = 0.9, offset = 0.05;
  ceres::CauchyLoss loss{3.0};
  ceres::Problem problem;
  explicit Chain(int n) : problem(Options()) {
    std::mt19937_64 rng(11);
    std::normal_distribution<double> noise(0.0, 1.0);
    std::vector<Eigen::Vector2d> truth(n);
    for (int i = 0; i < n; ++i) {
      const double a = 0.05 * i;
      truth[i] = Eigen::Vector2d(2.0 + std::cos(a), 1.0 + std::sin(1.7 * a));
    }
    for (int i = 0; i < n; ++i) {
      p.push_back(truth[i] + 0.05 * Eigen::Vector2d(noise(rng), noise(rng)));
    }
    for (int i = 0; i < n; ++i) {
      double beta = std::atan2(truth[i].y(), truth[i].x()) - 0.02 + 0.01 * noise(rng);
      if (i % 29 == 3) beta += 0.3;  // Outliers.
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<BearingTerm, 1, 2, 1>(new BearingTerm(beta)), &loss,
          p[i].data(), &offset);
      if (i > 0) {
        const Eigen::Vector2d u =
            (truth[i] - truth[i - 1]) / 1.1 + 0.002 * Eigen::Vector2d(noise(rng), noise(rng));
        problem.AddResidualBlock(
            new ceres::AutoDiffCostFunction<StepTerm, 2, 2, 2, 1>(new StepTerm(u, 0.002)), nullptr,
            p[i - 1].data(), p[i].data(), &scale);
      }
    }
    problem.SetManifold(p[0].data(), new ceres::SubsetManifold(2, {0}));
    problem.SetManifold(&scale, new PositiveManifold<1>());
  }
  static ceres::Problem::Options Options() {
    ceres::Problem::Options o;
    o.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    return o;
  }
  std::vector<double*> Latents() {
    std::vector<double*> latents;
    for (Eigen::Vector2d& v : p) latents.push_back(v.data());
    return latents;
  }
};

void SolveWithCeres(ceres::Problem* problem) {
  const ceres::Solver::Options options = band_arrow_test::TightCeresOptions();
  ceres::Solver::Summary summary;
  ceres::Solve(options, problem, &summary);
  ASSERT_TRUE(summary.IsSolutionUsable());
}

TEST(BandArrowCovarianceTest, BlockLatentsReachCeresOptimum) {
  Chain band(200), reference(200);
  const BandArrowOptions options = band_arrow_test::TightBandArrowOptions();
  BandArrowSummary summary;
  ASSERT_TRUE(SolveBandArrow(options, band.Latents(), "test", &band.problem, &summary).ok());
  EXPECT_TRUE(summary.converged);
  EXPECT_EQ(summary.band_width, 3);  // Two points of two columns each.
  SolveWithCeres(&reference.problem);
  EXPECT_NEAR(band.scale, reference.scale, 1e-8);
  EXPECT_NEAR(band.offset, reference.offset, 1e-8);
  EXPECT_EQ(band.p[0].x(), reference.p[0].x());  // Held by its manifold.
  for (size_t i = 0; i < band.p.size(); ++i)
    EXPECT_NEAR((band.p[i] - reference.p[i]).norm(), 0, 1e-7);
}

TEST(BandArrowCovarianceTest, MatchesCeresCovarianceAndItsLeverages) {
  Chain chain(200);
  SolveWithCeres(&chain.problem);
  // Globals, a latent with a manifold, two latents far apart (outside the band).
  const std::vector<const double*> blocks = {&chain.scale, &chain.offset, chain.p[0].data(),
                                             chain.p[7].data(), chain.p[150].data()};
  const StatusOr<BandArrowCovariance> ours =
      ComputeBandArrowCovariance(chain.Latents(), blocks, true, 2, &chain.problem);
  ASSERT_TRUE(ours.ok()) << ours.message();

  ceres::Covariance::Options covariance_options;
  covariance_options.algorithm_type = ceres::SPARSE_QR;
  ceres::Covariance covariance(covariance_options);
  std::set<std::pair<const double*, const double*>> pairs;
  const auto add = [&](const double* a, const double* b) {
    pairs.emplace(std::min(a, b), std::max(a, b));
  };
  for (size_t a = 0; a < blocks.size(); ++a) {
    for (size_t b = a; b < blocks.size(); ++b) add(blocks[a], blocks[b]);
  }
  for (size_t i = 0; i < chain.p.size(); ++i) {
    add(chain.p[i].data(), chain.p[i].data());
    if (i > 0) add(chain.p[i - 1].data(), chain.p[i].data());
    add(chain.p[i].data(), &chain.scale);
    add(chain.p[i].data(), &chain.offset);
  }
  ASSERT_TRUE(covariance.Compute(
      std::vector<std::pair<const double*, const double*>>(pairs.begin(), pairs.end()),
      &chain.problem));
  Eigen::Matrix<double, 8, 8, Eigen::RowMajor> joint;
  ASSERT_TRUE(covariance.GetCovarianceMatrix(blocks, joint.data()));
  const double norm = joint.norm();
  EXPECT_LT((ours->blocks - Eigen::MatrixXd(joint)).norm(), 1e-8 * norm) << ours->blocks << "\n\n"
                                                                         << joint;

  // Leverages: ρ′·tr(J·C·Jᵀ) from Ceres' blocks, for every residual; they sum to the free
  // parameters (2 per point, 1 for the first, and the two globals).
  std::vector<ceres::ResidualBlockId> ids;
  chain.problem.GetResidualBlocks(&ids);
  ASSERT_EQ(ours->leverages.size(), ids.size());
  double sum = 0.0;
  for (size_t t = 0; t < ids.size(); ++t) {
    std::vector<double*> values;
    chain.problem.GetParameterBlocksForResidualBlock(ids[t], &values);
    const ceres::CostFunction* cost = chain.problem.GetCostFunctionForResidualBlock(ids[t]);
    const int m = cost->num_residuals();
    int columns = 0;
    for (double* v : values) columns += chain.problem.ParameterBlockSize(v);
    Eigen::MatrixXd j(m, columns), c(columns, columns);
    std::vector<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> parts;
    std::vector<double*> jacobians;
    for (double* v : values) {
      parts.emplace_back(m, chain.problem.ParameterBlockSize(v));
      jacobians.push_back(parts.back().data());
    }
    Eigen::VectorXd r(m);
    ASSERT_TRUE(cost->Evaluate(values.data(), r.data(), jacobians.data()));
    int at = 0;
    for (size_t a = 0; a < values.size(); ++a) {
      j.middleCols(at, parts[a].cols()) = parts[a];
      int bt = 0;
      for (size_t b = 0; b < values.size(); ++b) {
        Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> block(
            parts[a].cols(), parts[b].cols());
        ASSERT_TRUE(covariance.GetCovarianceBlock(values[a], values[b], block.data()));
        c.block(at, bt, parts[a].cols(), parts[b].cols()) = block;
        bt += parts[b].cols();
      }
      at += parts[a].cols();
    }
    double rho[3] = {r.squaredNorm(), 1.0, 0.0};
    if (const ceres::LossFunction* loss = chain.problem.GetLossFunctionForResidualBlock(ids[t])) {
      loss->Evaluate(r.squaredNorm(), rho);
    }
    const double expected = rho[1] * (j * c * j.transpose()).trace();
    EXPECT_NEAR(ours->leverages[t], expected, 1e-7 * std::max(1.0, expected)) << t;
    sum += ours->leverages[t];
  }
  EXPECT_NEAR(sum, 2.0 * 200 - 1 + 2, 1e-6);
}

TEST(BandArrowCovarianceTest, SingularInformationIsNotObservable) {
  Chain chain(30);
  // With one bearing left, the first point's y, the scale and the offset are not determined.
  std::vector<ceres::ResidualBlockId> ids;
  chain.problem.GetResidualBlocks(&ids);
  const StatusOr<BandArrowCovariance> fine =
      ComputeBandArrowCovariance(chain.Latents(), {&chain.offset}, false, 1, &chain.problem);
  ASSERT_TRUE(fine.ok());
  for (const ceres::ResidualBlockId id : ids) {
    if (chain.problem.GetLossFunctionForResidualBlock(id) != nullptr) {
      chain.problem.RemoveResidualBlock(id);
    }
  }
  chain.problem.AddResidualBlock(
      new ceres::AutoDiffCostFunction<BearingTerm, 1, 2, 1>(new BearingTerm(0.1)), nullptr,
      chain.p[3].data(), &chain.offset);
  const StatusOr<BandArrowCovariance> singular =
      ComputeBandArrowCovariance(chain.Latents(), {&chain.offset}, true, 1, &chain.problem);
  EXPECT_EQ(singular.code(), StatusCode::kNotObservable) << singular.message();
}

}  // namespace
}  // namespace calib
