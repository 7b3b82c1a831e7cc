#ifndef CALIB_CORE_TIMING_BANDED_LDLT_H_
#define CALIB_CORE_TIMING_BANDED_LDLT_H_

#include <Eigen/Core>

// LDLᵀ of a symmetric positive-definite band matrix (half-bandwidth w): the information of the
// latent sample times, ordered by time, where each latent touches only its neighbours' intervals.
// O(n·w²) for the factorisation, the solves, the log-determinant and the band of the inverse
// (Takahashi's recurrences), which a general sparse factorisation does not give.
namespace calib {

class BandedLdlt {
 public:
  // `band` is (w + 1) × n with band(d, i) = A(i + d, i) (the lower half). False when A is not
  // positive definite.
  bool Compute(Eigen::MatrixXd band);

  Eigen::Index size() const { return factor_.cols(); }
  Eigen::Index bandwidth() const { return factor_.rows() - 1; }

  using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  // A⁻¹·B.
  Eigen::MatrixXd Solve(const Eigen::MatrixXd& b) const;
  // X ← A⁻¹·X, row-major: every column goes through each step at once, contiguous in memory.
  void SolveInPlace(RowMajorMatrix* x) const;
  // x ← A⁻¹·x for one column (as SolveInPlace, without its loop over columns).
  void SolveInPlace(Eigen::VectorXd* x) const;
  // log det A.
  double LogDeterminant() const;
  // diag(A⁻¹).
  Eigen::VectorXd InverseDiagonal() const;
  // A⁻¹ inside the band, stored like `band`: z(d, i) = A⁻¹(i + d, i).
  Eigen::MatrixXd InverseBand() const;

 private:
  Eigen::MatrixXd factor_;  // Row 0: D; rows d ≥ 1: L(i + d, i).
};

}  // namespace calib

#endif  // CALIB_CORE_TIMING_BANDED_LDLT_H_
