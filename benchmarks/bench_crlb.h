#ifndef CALIB_BENCHMARKS_BENCH_CRLB_H_
#define CALIB_BENCHMARKS_BENCH_CRLB_H_

#include <Eigen/Core>
#include <vector>

#include <calib/core/laser/laser_params.h>
#include <calib/core/laser/laser_log.h>
#include <calib/core/status.h>

namespace calib::bench {

// Cramér–Rao bound of the six parameters for a simulated log, at the truth, from the model's
// Jacobians (LaserResidual) and the TRUE noise: additive N(0, diag(scan_sigma²)) on sm and, when
// wheel_sigma > 0, N(0, wheel_sigma²) on each reported mean wheel speed. The true speeds are then
// nuisance parameters; eliminating them leaves per interval the information
//   J_pᵀ (A Σ_s Aᵀ + σ_w² J_φ J_φᵀ)⁻¹ J_p,
// with A the rotation that carries sm noise into the residual. Intervals with skip[k] true
// (outliers) are left out. Returns the 6×6 covariance bound.
//
// When `diagonal_weighted` is not null it receives the asymptotic covariance of the weighted
// least-squares estimate that whitens the residual e = ŝ⁻¹ ∘ sm with diag(1/scan_sigma), as
// LaserResidual does with a known noise level: H⁻¹·Σ Jᵀ W Σ_e W J·H⁻¹ with H = Σ Jᵀ W J. It
// equals the bound when that weighting is the true one, and shows the loss when it is not.
StatusOr<LaserParamMatrix> LaserCramerRaoBound(const std::vector<LaserInterval>& intervals,
                                               const std::vector<bool>& skip,
                                               const LaserCalibration& truth,
                                               const Eigen::Vector3d& scan_sigma,
                                               double wheel_sigma,
                                               LaserParamMatrix* diagonal_weighted = nullptr);

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_CRLB_H_
