#ifndef CALIB_SOLVERS_TIMING_LATENT_TIME_STATISTICS_H_
#define CALIB_SOLVERS_TIMING_LATENT_TIME_STATISTICS_H_

#include <calib/core/status.h>
#include <calib/solvers/timing/latent_time_problem.h>

#include <Eigen/Core>

// Statistics of the latent sample times at a linearisation of the timing-aware problem: the
// jitter scales as variance components (the σ's that maximise the evidence of the latents, i.e.
// the data with the latents integrated out), and the covariance of the globals with the latents
// marginalised (their Schur complement, exact thanks to the band structure).
namespace calib {

// The prior of each latent: mean (τ for sensor latents, 0 for encoder ones) and σ.
struct LatentPrior {
  Eigen::VectorXd mean;
  Eigen::VectorXd sigma;
};
LatentPrior MakeLatentPrior(const LatentLinearization& lin, double offset_s, double sensor_sigma_s,
                            double encoder_sigma_s);

// −2 log of the evidence p(data | σ) at fixed globals, up to a constant: for the linearised
// residual r(x) = r̂ + J(x − x̂) and the prior x ~ N(m, Λ⁻¹),
//   −g̃ᵀ(H + Λ)⁻¹g̃ + log det(H + Λ) − log det Λ,   g̃ = Jᵀr̂ + H(m − x̂),  H = JᵀJ.
StatusOr<double> LatentNegLogEvidence(const LatentLinearization& lin, const LatentPrior& prior);

struct JitterScales {
  double sensor_s = 0.0;
  double encoder_s = 0.0;
};
// The σ's that maximise the evidence (coordinate-wise: a log grid, then golden section), each in
// [floor, ceiling]; those not fitted keep their values.
JitterScales MaximizeLatentEvidence(const LatentLinearization& lin, double offset_s,
                                    JitterScales initial, bool fit_sensor, bool fit_encoder,
                                    double floor_s, double ceiling_s);

struct LatentCovariance {
  Eigen::MatrixXd globals;          // G × G, tangent space (see odometry_plus_jacobian).
  Eigen::VectorXd latent_variance;  // Marginal variance of each latent.
  double effective_latents = 0.0;   // Σ(1 − Var_i/σ_i²): the latents' share of the fit.
  double log_det = 0.0;             // log det(H_ll + Λ).
};
StatusOr<LatentCovariance> MarginalLatentCovariance(const LatentLinearization& lin,
                                                    const LatentPrior& prior);

}  // namespace calib

#endif  // CALIB_SOLVERS_TIMING_LATENT_TIME_STATISTICS_H_
