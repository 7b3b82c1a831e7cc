#ifndef CALIB_SOLVERS_TIMING_LATENT_ERROR_COVARIANCE_H_
#define CALIB_SOLVERS_TIMING_LATENT_ERROR_COVARIANCE_H_

#include <calib/core/status.h>
#include <calib/solvers/timing/latent_time_problem.h>
#include <calib/solvers/timing/latent_time_statistics.h>

#include <Eigen/Core>
#include <vector>

// What the latent-time model's error assumptions leave out of the globals' covariance C: errors
// of the regressors (the wheel angles between polls) and errors shared by neighbouring intervals
// (scan poses with independent errors). Each moves the globals through the profile Jacobian
// J̃ = J_g − J_l·X of the intervals it enters (the latents following), so it adds C·(ΣJ̃ᵀ·E·J̃)·C.
// `lin` from Linearize(true), `covariance` from MarginalLatentCovariance.
namespace calib {

// What the wheel angles between polls add: each sample's angles err by σ
// (LatentLinearization::sample_angle) through the one or two intervals they end. The errors of
// one segment and wheel move together (one jump of the acceleration between two polls), the
// segments and wheels independently. Zero without the cubic.
StatusOr<Eigen::MatrixXd> LatentAngleCovariance(const LatentLinearization& lin,
                                                const LatentCovariance& covariance);

// Lag-1 correlation of the whitened interval errors (x, y, θ) between intervals that share a
// sample, errors beyond 3σ left out: near 0 for an incremental scan matcher, whose displacements
// err independently; −1/2 for scan poses that err independently (against a map, or a simulator's
// pose noise), where a pose's error enters the interval before it and the one after it.
struct NeighbourCorrelation {
  Eigen::Matrix3d correlation = Eigen::Matrix3d::Zero();  // (c, d): error_k(c)·error_k+1(d).
  int pairs = 0;
  // Both translation components below −0.25 over at least 30 pairs: the poses' own errors.
  bool PoseErrors() const;
};
NeighbourCorrelation NeighbourErrorCorrelation(const std::vector<Eigen::Vector3d>& errors,
                                               const Eigen::Vector3d& noise_sigma,
                                               const std::vector<int>& interval_start);

// What that correlation R adds: C·Σ_k (J̃_kᵀ·R·J̃_k+1 + J̃_k+1ᵀ·Rᵀ·J̃_k)·C over the intervals k,
// k + 1 that share a sample (negative for pose errors: the low frequencies cancel).
StatusOr<Eigen::MatrixXd> LatentNeighbourCovariance(const LatentLinearization& lin,
                                                    const LatentCovariance& covariance,
                                                    const Eigen::Matrix3d& correlation);

}  // namespace calib

#endif  // CALIB_SOLVERS_TIMING_LATENT_ERROR_COVARIANCE_H_
