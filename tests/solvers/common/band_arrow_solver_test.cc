#include <calib/problems/positive_manifold.h>
#include <calib/solvers/common/band_arrow_solver.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "tests/solvers/common/band_arrow_test_options.h"

namespace calib {
namespace {

// y_i = s·x_i + c (robust: a few outliers), x_{i+1} − x_i = v and a stamp z_i = x_i + noise:
// latents x_i in a chain (band width 1), a positive global s and a plain global (c, v).
struct Measurement {
  Measurement(double y, double sigma) : y(y), sigma(sigma) {}
  template <typename T>
  bool operator()(const T* x, const T* scale, const T* shift, T* r) const {
    r[0] = (scale[0] * x[0] + shift[0] - T(y)) / T(sigma);
    return true;
  }
  double y, sigma;
};

struct Step {
  explicit Step(double sigma) : sigma(sigma) {}
  template <typename T>
  bool operator()(const T* a, const T* b, const T* shift, T* r) const {
    r[0] = (b[0] - a[0] - shift[1]) / T(sigma);
    return true;
  }
  double sigma;
};

struct Stamp {
  explicit Stamp(double z) : z(z) {}
  template <typename T>
  bool operator()(const T* x, T* r) const {
    r[0] = (x[0] - T(z)) / T(0.2);
    return true;
  }
  double z;
};

struct Problem {
  std::vector<double> x;
  double scale = 1.0;
  double shift[2] = {0.0, 0.0};
  ceres::CauchyLoss loss{2.0};
  ceres::Problem problem;
  explicit Problem(int n) : problem(Options()) {
    std::mt19937_64 rng(7);
    std::normal_distribution<double> noise(0.0, 0.05);
    x.assign(n, 0.0);
    for (int i = 0; i < n; ++i) {
      const double truth = 0.3 * i + std::sin(0.1 * i);
      double y = 2.5 * truth + 1.0 + noise(rng);
      if (i % 37 == 5) y += 3.0;  // Outliers.
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<Stamp, 1, 1>(new Stamp(truth + 0.2 * noise(rng) / 0.05)),
          nullptr, &x[i]);
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<Measurement, 1, 1, 1, 2>(new Measurement(y, 0.05)), &loss,
          &x[i], &scale, shift);
    }
    for (int i = 0; i + 1 < n; ++i) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Step, 1, 1, 1, 2>(new Step(0.5)),
                               nullptr, &x[i], &x[i + 1], shift);
    }
    problem.SetManifold(&scale, new PositiveManifold<1>());
  }
  static ceres::Problem::Options Options() {
    ceres::Problem::Options o;
    o.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    return o;
  }
  std::vector<double*> Latents() {
    std::vector<double*> latents;
    for (double& v : x) latents.push_back(&v);
    return latents;
  }
};

TEST(BandArrowSolverTest, ReachesCeresOptimum) {
  Problem band(300), reference(300);
  const BandArrowOptions options = band_arrow_test::TightBandArrowOptions();
  BandArrowSummary summary;
  ASSERT_TRUE(SolveBandArrow(options, band.Latents(), "test", &band.problem, &summary).ok());
  EXPECT_TRUE(summary.converged);
  EXPECT_EQ(summary.band_width, 1);
  EXPECT_LT(summary.final_cost, summary.initial_cost);

  const ceres::Solver::Options ceres_options = band_arrow_test::TightCeresOptions();
  ceres::Solver::Summary ceres_summary;
  ceres::Solve(ceres_options, &reference.problem, &ceres_summary);
  EXPECT_NEAR(summary.final_cost, ceres_summary.final_cost, 1e-8 * ceres_summary.final_cost);
  EXPECT_NEAR(band.scale, reference.scale, 1e-7);
  EXPECT_NEAR(band.shift[0], reference.shift[0], 1e-6);
  EXPECT_NEAR(band.shift[1], reference.shift[1], 1e-7);
  for (size_t i = 0; i < band.x.size(); ++i) EXPECT_NEAR(band.x[i], reference.x[i], 1e-6);
  EXPECT_NEAR(band.scale, 2.5, 0.01);
}

// With a global-step tolerance, two accepted steps that move the globals by less than it (in σ of
// their marginal information) end the solve: a huge one stops after the second accepted step.
TEST(BandArrowSolverTest, GlobalStepToleranceStopsOnceTheGlobalsSettle) {
  Problem loose(300), tight(300);
  BandArrowOptions options;
  options.function_tolerance = 1e-14;
  options.max_iterations = 200;
  BandArrowSummary reference;
  ASSERT_TRUE(SolveBandArrow(options, tight.Latents(), "test", &tight.problem, &reference).ok());
  options.global_step_tolerance = 1e9;
  BandArrowSummary summary;
  ASSERT_TRUE(SolveBandArrow(options, loose.Latents(), "test", &loose.problem, &summary).ok());
  EXPECT_TRUE(summary.converged);
  EXPECT_LT(summary.iterations, reference.iterations);
  EXPECT_LT(summary.final_cost, summary.initial_cost);
  EXPECT_GT(summary.final_cost, reference.final_cost);
}

TEST(BandArrowSolverTest, ConstantBlocksStayPut) {
  Problem band(100);
  band.problem.SetParameterBlockConstant(&band.scale);
  band.x[10] = 0.123;
  band.problem.SetParameterBlockConstant(&band.x[10]);
  BandArrowSummary summary;
  ASSERT_TRUE(
      SolveBandArrow(BandArrowOptions(), band.Latents(), "test", &band.problem, &summary).ok());
  EXPECT_EQ(band.scale, 1.0);
  EXPECT_EQ(band.x[10], 0.123);
  EXPECT_LT(summary.final_cost, summary.initial_cost);
}

// The same problem listed as ArrowTerms (blocks in the problem's order, constants kept) solves to
// the same point; a residual on a block that is not listed is refused.
TEST(BandArrowSolverTest, ListedTermsSolveAsTheProblem) {
  Problem from_problem(200), from_lists(200);
  from_problem.problem.SetParameterBlockConstant(&from_problem.x[3]);
  from_lists.problem.SetParameterBlockConstant(&from_lists.x[3]);
  const ArrowTerms terms = ArrowTerms::FromProblem(from_lists.problem);
  ASSERT_EQ(terms.num_residuals(), static_cast<size_t>(from_lists.problem.NumResidualBlocks()));
  const BandArrowOptions options = band_arrow_test::TightBandArrowOptions();
  BandArrowSummary expected, summary;
  ASSERT_TRUE(
      SolveBandArrow(options, from_problem.Latents(), "test", &from_problem.problem, &expected)
          .ok());
  BandArrowSolver solver;
  ASSERT_TRUE(solver.Build(from_lists.Latents(), terms).ok());
  ASSERT_TRUE(solver.Solve(options, "test", &summary).ok());
  EXPECT_EQ(summary.iterations, expected.iterations);
  EXPECT_EQ(summary.final_cost, expected.final_cost);
  EXPECT_EQ(from_lists.scale, from_problem.scale);
  EXPECT_EQ(from_lists.x[3], 0.0);

  // Back to a Ceres problem: the same blocks, residuals and constants.
  const std::unique_ptr<ceres::Problem> rebuilt = terms.ToProblem();
  EXPECT_EQ(rebuilt->NumResidualBlocks(), from_lists.problem.NumResidualBlocks());
  EXPECT_EQ(rebuilt->NumParameterBlocks(), from_lists.problem.NumParameterBlocks());
  EXPECT_TRUE(rebuilt->IsParameterBlockConstant(&from_lists.x[3]));
  EXPECT_NE(rebuilt->GetManifold(&from_lists.scale), nullptr);

  ArrowTerms missing = terms;
  missing.blocks.erase(missing.blocks.begin());  // x[0], which residuals use.
  BandArrowSolver refused;
  const Status status = refused.Build(from_lists.Latents(), missing);
  EXPECT_EQ(status.code(), StatusCode::kInternal);
  EXPECT_NE(status.message().find("unlisted block"), std::string::npos);
}

}  // namespace
}  // namespace calib
