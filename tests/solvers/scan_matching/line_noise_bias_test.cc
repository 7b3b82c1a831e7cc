#include <calib/solvers/scan_matching/line_noise_bias.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <vector>

namespace calib {
namespace {

// Gauss–Hermite nodes and weights for E[f(e)], e ~ N(0, 1) (Golub–Welsch).
void StandardNormalQuadrature(int n, std::vector<double>* nodes, std::vector<double>* weights) {
  Eigen::MatrixXd jacobi = Eigen::MatrixXd::Zero(n, n);
  for (int k = 1; k < n; ++k) jacobi(k, k - 1) = jacobi(k - 1, k) = std::sqrt(1.0 * k);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(jacobi);
  nodes->clear();
  weights->clear();
  for (int i = 0; i < n; ++i) {
    nodes->push_back(eigen.eigenvalues()(i));
    weights->push_back(eigen.eigenvectors()(0, i) * eigen.eigenvectors()(0, i));
  }
}

// E[J r] by quadrature over the three ranges' noise: the residual and Jacobian as the matcher
// forms them, r = n·(R p + t − q_a), J = (n, n·(R p)^⊥), n the noisy line's normal.
Eigen::Vector3d QuadratureBias(const Eigen::Vector2d& qa, const Eigen::Vector2d& qb,
                               const Eigen::Vector2d& rotated_point, const Eigen::Vector2d& t,
                               double sigma) {
  std::vector<double> x, w;
  StandardNormalQuadrature(24, &x, &w);
  const Eigen::Vector2d ua = qa.normalized(), ub = qb.normalized();
  const Eigen::Vector2d up = rotated_point.normalized();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < x.size(); ++i) {
    for (size_t j = 0; j < x.size(); ++j) {
      for (size_t k = 0; k < x.size(); ++k) {
        const Eigen::Vector2d a = qa + sigma * x[i] * ua, b = qb + sigma * x[j] * ub;
        const Eigen::Vector2d p = rotated_point + sigma * x[k] * up;
        const Eigen::Vector2d along = (b - a).normalized();
        const Eigen::Vector2d n(-along.y(), along.x());
        const double r = n.dot(p + t - a);
        const Eigen::Vector3d jac(n.x(), n.y(), n.dot(Eigen::Vector2d(-p.y(), p.x())));
        sum += w[i] * w[j] * w[k] * jac * r;
      }
    }
  }
  return sum;
}

// The second-order formula against the expectation itself, on oblique lines seen from the
// sensor at the origin, with the current point at several places along the segment: within 2 %
// at σ = ℓ/100 (the next order is (σ/ℓ)² smaller).
TEST(LineNoiseBiasTest, MatchesTheExpectationOverTheRangeNoise) {
  const Eigen::Vector2d t(0.1, -0.2);  // The current sensor in the reference frame.
  double largest = 0.0;                // Of |E[J r]| in units of σ²/ℓ.
  for (const double angle : {0.3, 1.0, -0.7}) {
    const Eigen::Vector2d mid(3.0, 1.0), along(std::cos(angle), std::sin(angle));
    const Eigen::Vector2d qa = mid - 0.05 * along, qb = mid + 0.05 * along;
    for (const double alpha : {0.2, 0.5, 0.9}) {
      const Eigen::Vector2d point = qa + alpha * (qb - qa);  // On the true line.
      const Eigen::Vector2d rotated_point = point - t;
      const double sigma = 1e-3;
      const Eigen::Vector3d expected = QuadratureBias(qa, qb, rotated_point, t, sigma);
      const Eigen::Vector3d formula =
          LineNoiseGradientBias(qa, qb, qa.normalized(), qb.normalized(), alpha, rotated_point,
                                rotated_point.normalized(), sigma);
      largest = std::max(largest, expected.norm() / (sigma * sigma / 0.1));
      EXPECT_LT((formula - expected).norm(), 0.02 * expected.norm())
          << "angle " << angle << " alpha " << alpha << ": formula " << formula.transpose()
          << ", expectation " << expected.transpose();
    }
  }
  EXPECT_GT(largest, 0.5);  // A bias of the order of σ²/ℓ, worth taking out.
}

TEST(LineNoiseBiasTest, NoNoiseNoBias) {
  const Eigen::Vector2d qa(3.0, 0.0), qb(3.0, 0.1), p(2.9, 0.04);
  EXPECT_EQ(
      LineNoiseGradientBias(qa, qb, qa.normalized(), qb.normalized(), 0.4, p, p.normalized(), 0.0),
      Eigen::Vector3d::Zero());
}

}  // namespace
}  // namespace calib
