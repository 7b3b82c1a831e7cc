#ifndef CALIB_CORE_WHITENING_H_
#define CALIB_CORE_WHITENING_H_

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>

namespace calib {

// The upper-triangular square root L of the information Σ⁻¹ (LᵀL = Σ⁻¹), so that L·e has unit
// covariance when e has covariance Σ. Σ must be symmetric positive definite.
template <int N>
Eigen::Matrix<double, N, N> SqrtInformation(const Eigen::Matrix<double, N, N>& covariance) {
  const Eigen::Matrix<double, N, N> information =
      covariance.inverse().eval().template selfadjointView<Eigen::Lower>();
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt(information);
  return llt.matrixU();
}

}  // namespace calib

#endif  // CALIB_CORE_WHITENING_H_
