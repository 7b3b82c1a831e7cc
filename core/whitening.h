#ifndef CALIB_CORE_WHITENING_H_
#define CALIB_CORE_WHITENING_H_

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <cmath>

namespace calib {

// The upper-triangular square root L of the information Σ⁻¹ (LᵀL = Σ⁻¹), so that L·e has unit
// covariance when e has covariance Σ. Σ must be symmetric positive definite.
//
// Up to 3×3 the Cholesky factor is Eigen's unblocked LLT written out in fixed sizes, the same
// operations in the same order (the same bits), without its dynamic blocks: a per-interval
// whitening costs a fifth. Larger, or where the factorization breaks down (Σ not numerically
// positive definite), Eigen's LLT itself.
template <int N>
Eigen::Matrix<double, N, N> SqrtInformation(const Eigen::Matrix<double, N, N>& covariance) {
  const Eigen::Matrix<double, N, N> information =
      covariance.inverse().eval().template selfadjointView<Eigen::Lower>();
  const auto eigens = [&information]() -> Eigen::Matrix<double, N, N> {
    return Eigen::LLT<Eigen::Matrix<double, N, N>>(information).matrixU();
  };
  // Beyond 3, Eigen sums the squares in SIMD packets: its order is not this loop's.
  if constexpr (N > 3) return eigens();
  Eigen::Matrix<double, N, N> lower = Eigen::Matrix<double, N, N>::Zero();
  for (int k = 0; k < N; ++k) {
    double sum = 0.0;
    for (int j = 0; j < k; ++j) sum += lower(k, j) * lower(k, j);
    double x = information(k, k);
    if (k > 0) x -= sum;
    if (!(x > 0.0)) return eigens();
    x = std::sqrt(x);
    lower(k, k) = x;
    for (int i = k + 1; i < N; ++i) {
      double a = information(i, k);
      for (int j = 0; j < k; ++j) a -= lower(i, j) * lower(k, j);
      lower(i, k) = a / x;
    }
  }
  return lower.transpose();
}

}  // namespace calib

#endif  // CALIB_CORE_WHITENING_H_
