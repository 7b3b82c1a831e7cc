#include <calib/solvers/timing/latent_error_covariance.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <random>
#include <vector>

namespace calib {
namespace {

struct Errors {
  std::vector<Eigen::Vector3d> errors;
  std::vector<int> interval_start;
};

// Interval errors of n intervals between consecutive samples: from poses that err independently
// (e_k = n_k+1 − n_k) or from an incremental matcher (e_k independent).
Errors Simulated(int n, bool pose_errors, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  const Eigen::Vector3d sigma(1e-3, 1e-3, 2e-3);
  const auto draw = [&] {
    return Eigen::Vector3d(sigma(0) * normal(rng), sigma(1) * normal(rng), sigma(2) * normal(rng));
  };
  Errors out;
  Eigen::Vector3d pose = draw();
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d next = draw();
    out.errors.push_back(pose_errors ? Eigen::Vector3d(next - pose) : next);
    out.interval_start.push_back(k);
    pose = next;
  }
  return out;
}

TEST(NeighbourErrorCorrelation, PoseErrorsCorrelateByMinusOneHalf) {
  const Errors e = Simulated(4000, true, 1);
  const NeighbourCorrelation c = NeighbourErrorCorrelation(
      e.errors, Eigen::Vector3d(1.4e-3, 1.4e-3, 2.8e-3), e.interval_start);
  EXPECT_GT(c.pairs, 3900);  // Pairs with an error beyond 3σ are left out.
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(c.correlation(d, d), -0.5, 0.05);
  EXPECT_NEAR(c.correlation(0, 1), 0.0, 0.05);
  EXPECT_TRUE(c.PoseErrors());
}

TEST(NeighbourErrorCorrelation, IncrementalMatcherErrorsDoNot) {
  const Errors e = Simulated(4000, false, 2);
  const NeighbourCorrelation c =
      NeighbourErrorCorrelation(e.errors, Eigen::Vector3d(1e-3, 1e-3, 2e-3), e.interval_start);
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(c.correlation(d, d), 0.0, 0.05);
  EXPECT_FALSE(c.PoseErrors());
}

// Intervals that do not share a sample (a dropped sample between them) are no pair.
TEST(NeighbourErrorCorrelation, OnlyIntervalsThatShareASamplePair) {
  Errors e = Simulated(100, true, 3);
  for (size_t k = 0; k < e.interval_start.size(); ++k)
    e.interval_start[k] = 2 * static_cast<int>(k);
  const NeighbourCorrelation c = NeighbourErrorCorrelation(
      e.errors, Eigen::Vector3d(1.4e-3, 1.4e-3, 2.8e-3), e.interval_start);
  EXPECT_EQ(c.pairs, 0);
  EXPECT_FALSE(c.PoseErrors());
}

}  // namespace
}  // namespace calib
