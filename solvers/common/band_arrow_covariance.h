#ifndef CALIB_SOLVERS_COMMON_BAND_ARROW_COVARIANCE_H_
#define CALIB_SOLVERS_COMMON_BAND_ARROW_COVARIANCE_H_

#include <calib/core/status.h>
#include <ceres/ceres.h>

#include <Eigen/Core>
#include <vector>

// The covariance of a band-arrow problem (solvers/common/band_arrow_solver.h: a few global
// blocks, many latent blocks in a band order) in O(n·w²), where ceres::Covariance pays a sparse
// back-solve for every column it is asked for (quadratic when every latent's leverage is needed).
namespace calib {

struct BandArrowCovariance {
  // Of the requested blocks, jointly, in their ambient coordinates and order (as
  // ceres::Covariance::GetCovarianceMatrix gives it; zeros for constant blocks).
  Eigen::MatrixXd blocks;
  // Per residual block in the problem's order (when asked): its leverage ρ′·tr(J·Σ·Jᵀ), Σ the
  // covariance of its non-constant blocks; they sum to the number of free tangent parameters.
  std::vector<double> leverages;
};

// At the current values of `problem`, with ρ′JᵀJ as the information (what ceres::Covariance
// uses for losses with ρ″ ≤ 0, such as Cauchy). `latents` as for SolveBandArrow. kNotObservable
// when the information is singular.
StatusOr<BandArrowCovariance> ComputeBandArrowCovariance(const std::vector<double*>& latents,
                                                         const std::vector<const double*>& blocks,
                                                         bool with_leverages, int num_threads,
                                                         ceres::Problem* problem);

}  // namespace calib

#endif  // CALIB_SOLVERS_COMMON_BAND_ARROW_COVARIANCE_H_
