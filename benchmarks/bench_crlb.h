#ifndef CALIB_BENCHMARKS_BENCH_CRLB_H_
#define CALIB_BENCHMARKS_BENCH_CRLB_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/laser/laser_params.h>
#include <calib/core/status.h>

#include <Eigen/Core>
#include <vector>

namespace calib::bench {

// The true noise of a simulated log: additive N(0, diag(scan_sigma²)) on sm and, when
// wheel_sigma > 0, N(0, wheel_sigma²) on each reported mean wheel speed.
struct LaserNoiseModel {
  Eigen::Vector3d scan_sigma = Eigen::Vector3d::Zero();
  double wheel_sigma = 0.0;
};

struct LaserCramerRao {
  LaserParamMatrix bound;  // The 6×6 covariance bound.
  // The asymptotic covariance of the weighted least-squares estimate that whitens the residual
  // e = ŝ⁻¹ ∘ sm with diag(1/scan_sigma), as LaserResidual does with a known noise level:
  // H⁻¹·Σ Jᵀ W Σ_e W J·H⁻¹ with H = Σ Jᵀ W J. It equals the bound when that weighting is the
  // true one, and shows the loss when it is not.
  LaserParamMatrix diagonal_weighted;
};

// Cramér–Rao bound of the six parameters for a simulated log, at the truth, from the model's
// Jacobians (LaserResidual) and the TRUE noise. With wheel-speed noise the true speeds are
// nuisance parameters; eliminating them leaves per interval the information
//   J_pᵀ (A Σ_s Aᵀ + σ_w² J_φ J_φᵀ)⁻¹ J_p,
// with A the rotation that carries sm noise into the residual. Intervals with skip[k] true
// (outliers) are left out.
StatusOr<LaserCramerRao> LaserCramerRaoBound(const std::vector<LaserInterval>& intervals,
                                             const std::vector<bool>& skip,
                                             const LaserCalibration& truth,
                                             const LaserNoiseModel& noise);

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_CRLB_H_
