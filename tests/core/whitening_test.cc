// The whitening's square root of the information: LᵀL = Σ⁻¹ with L upper triangular, the same
// bits as Eigen's LLT (which it writes out), and Eigen's own answer where Σ is not numerically
// positive definite.
#include <calib/core/whitening.h>
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <random>

namespace calib {
namespace {

template <int N>
Eigen::Matrix<double, N, N> EigensRoot(const Eigen::Matrix<double, N, N>& covariance) {
  const Eigen::Matrix<double, N, N> information =
      covariance.inverse().eval().template selfadjointView<Eigen::Lower>();
  return Eigen::LLT<Eigen::Matrix<double, N, N>>(information).matrixU();
}

template <int N>
void ExpectEigensBits(unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::Matrix<double, N, N> a;
    for (int i = 0; i < N * N; ++i) a(i) = uniform(rng);
    // Scales from 1e-6 to 1 per axis, as noise variances of metres and radians are.
    Eigen::Matrix<double, N, 1> scale;
    for (int i = 0; i < N; ++i) scale(i) = std::pow(10.0, -6.0 * (uniform(rng) + 1.0) / 2.0);
    const Eigen::Matrix<double, N, N> covariance =
        scale.asDiagonal() * (a * a.transpose() + 0.1 * Eigen::Matrix<double, N, N>::Identity()) *
        scale.asDiagonal();
    const Eigen::Matrix<double, N, N> root = SqrtInformation<N>(covariance);
    EXPECT_TRUE((root.array() == EigensRoot<N>(covariance).array()).all()) << N << " " << trial;
    EXPECT_TRUE(root.isUpperTriangular());
    const Eigen::Matrix<double, N, N> identity = root * covariance * root.transpose();
    EXPECT_TRUE(identity.isIdentity(1e-9)) << identity;
  }
}

TEST(WhiteningTest, TheRootIsEigensLltBitForBit) {
  ExpectEigensBits<1>(1);
  ExpectEigensBits<2>(2);
  ExpectEigensBits<3>(3);
  ExpectEigensBits<6>(4);  // Eigen's own LLT there.
}

TEST(WhiteningTest, ANonPositiveDefiniteCovarianceGetsEigensAnswer) {
  Eigen::Matrix3d covariance;
  covariance << 1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 1.0;
  const Eigen::Matrix3d root = SqrtInformation<3>(covariance);
  const Eigen::Matrix3d eigens = EigensRoot<3>(covariance);
  for (int i = 0; i < 9; ++i) {
    EXPECT_TRUE(root(i) == eigens(i) || (std::isnan(root(i)) && std::isnan(eigens(i)))) << i;
  }
}

}  // namespace
}  // namespace calib
