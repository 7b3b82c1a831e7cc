#ifndef CALIB_SOLVERS_COMMON_SUITESPARSE_ALIGNMENT_H_
#define CALIB_SOLVERS_COMMON_SUITESPARSE_ALIGNMENT_H_

namespace calib {

// Puts SuiteSparse's blocks (CHOLMOD's, SPQR's: Ceres' sparse solves and ceres::Covariance) on
// 64-byte boundaries from then on. The BLAS kernels beneath take paths that depend on their
// operands' alignment, and malloc's 16-byte blocks fall on other boundaries from run to run as
// other threads allocate meanwhile: a bearing covariance differed in its last bits between runs
// of the same log. Idempotent and thread-safe (MakeSolverOptions and MakeCovarianceOptions call
// it); the blocks stay free()-compatible, as Ceres frees some of SPQR's outputs itself.
void AlignSuiteSparseAllocations();

}  // namespace calib

#endif  // CALIB_SOLVERS_COMMON_SUITESPARSE_ALIGNMENT_H_
