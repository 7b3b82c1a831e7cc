#include <calib/core/timing/banded_ldlt.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>

namespace calib {
namespace {

TEST(BandedLdlt, MatchesDenseSolveDeterminantAndInverseBand) {
  const int n = 40, w = 3;
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
  std::srand(3);
  for (int i = 0; i < n; ++i) {
    for (int j = i; j < std::min(n, i + w + 1); ++j)
      a(i, j) = a(j, i) = Eigen::internal::random<double>(-1, 1);
    a(i, i) += 2.0 * w + 1.0;
  }
  Eigen::MatrixXd band = Eigen::MatrixXd::Zero(w + 1, n);
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d <= w && i + d < n; ++d) band(d, i) = a(i + d, i);
  }
  BandedLdlt ldlt;
  ASSERT_TRUE(ldlt.Compute(band));
  const Eigen::MatrixXd b = Eigen::MatrixXd::Random(n, 2);
  EXPECT_LT((ldlt.Solve(b) - a.ldlt().solve(b)).cwiseAbs().maxCoeff(), 1e-12);
  // One column in place: the same numbers as the matrix solve's column.
  Eigen::VectorXd x = b.col(1);
  ldlt.SolveInPlace(&x);
  EXPECT_EQ(x, ldlt.Solve(b).col(1));
  EXPECT_NEAR(ldlt.LogDeterminant(), std::log(a.determinant()), 1e-9);
  EXPECT_LT((ldlt.InverseDiagonal() - a.inverse().diagonal()).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::MatrixXd inverse = a.inverse();
  const Eigen::MatrixXd z = ldlt.InverseBand();
  for (int i = 0; i < n; ++i) {
    for (int d = 0; d <= w && i + d < n; ++d) EXPECT_NEAR(z(d, i), inverse(i + d, i), 1e-12);
  }
}

TEST(BandedLdlt, RejectsIndefinite) {
  Eigen::MatrixXd band(2, 2);
  band << 1.0, 1.0, 2.0, 0.0;  // [[1, 2], [2, 1]].
  BandedLdlt ldlt;
  EXPECT_FALSE(ldlt.Compute(band));
}

}  // namespace
}  // namespace calib
