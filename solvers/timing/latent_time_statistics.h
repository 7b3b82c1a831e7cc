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

// The variance components: scan noise (x, y, θ) and the jitter of sensor and encoder times.
struct NoiseScales {
  Eigen::Vector3d scan = Eigen::Vector3d::Ones();
  double sensor_s = 0.0;
  double encoder_s = 0.0;
};

// −2 log of the evidence p(data | scales) at fixed globals, up to a constant, with the latents x
// integrated out of the linearised problem (residual rows rescaled to the scan noise `scales`):
//   min_x [Σ‖r + J(x − x̂)‖² + ‖x − m‖²_Λ] + log det(H + Λ) − log det Λ + N·log det Σ_scan.
// The scan noise must come from here, not from the fitted residuals: the latents absorb the
// rotation errors they can explain, and a noise level re-estimated from what they leave feeds
// back into ever freer latents (an incidental-parameter collapse that biases b).
StatusOr<double> LatentNegLogEvidence(const LatentLinearization& lin, double offset_s,
                                      const NoiseScales& scales);
// The same with its gradient in (log σ_x, log σ_y, log σ_θ, log σ_sensor, log σ_encoder).
struct LatentEvidence {
  double value = 0.0;
  Eigen::Matrix<double, 5, 1> gradient = Eigen::Matrix<double, 5, 1>::Zero();
};
StatusOr<LatentEvidence> LatentEvidenceWithGradient(const LatentLinearization& lin, double offset_s,
                                                    const NoiseScales& scales, bool with_gradient);

// The scales that maximise the evidence, jointly (the scan's rotation noise and the jitters trade
// off, which coordinate-wise searches resolve only slowly): projected Newton in log σ on the
// analytic gradient, scan noise within [1/8, 8] of the starting one, jitters in [floor, ceiling];
// those not fitted keep their values.
struct NoiseScaleFit {
  bool scan = true, sensor = true, encoder = true;
  double floor_s = 1e-4, ceiling_s = 1.0;
  int num_threads = 1;  // For the Hessian's columns.
};
// `gain`, when given: how much −2 log evidence fell from `initial` to the result.
NoiseScales MaximizeLatentEvidence(const LatentLinearization& lin, double offset_s,
                                   NoiseScales initial, const NoiseScaleFit& fit,
                                   double* gain = nullptr);

struct LatentCovariance {
  Eigen::MatrixXd globals;          // G × G, tangent space (see odometry_plus_jacobian).
  Eigen::VectorXd latent_variance;  // Marginal variance of each latent.
  double effective_latents = 0.0;   // Σ(1 − Var_i/σ_i²): the latents' share of the fit.
  double log_det = 0.0;             // log det(H_ll + Λ).
  Eigen::MatrixXd latent_gain;  // X = (H_ll + Λ)⁻¹H_lg (L × G): the latents' share of a step.
};
StatusOr<LatentCovariance> MarginalLatentCovariance(const LatentLinearization& lin,
                                                    const LatentPrior& prior);

// Each interval's profile score u_i = g_i − Xᵀl_i (intervals × G): its gradient contribution to
// the globals (g_i) and to the latents (l_i), through X = latent_gain (how the latents follow the
// globals), the latents' priors counted in the row of their first interval. They sum to the
// gradient of the globals with the latents optimised: 0 at the optimum. `lin` from
// Linearize(true).
StatusOr<Eigen::MatrixXd> LatentProfileScores(const LatentLinearization& lin,
                                              const LatentPrior& prior,
                                              const LatentCovariance& covariance);

// The globals' cluster-robust (sandwich) covariance C·V·C·n/r, C = covariance.globals (the
// inverse of their information with the latents marginalised), V the long-run covariance
// (Bartlett, `lag` intervals) of the profile scores. It stays honest where the residuals hold
// structure the model leaves out that follows a global; n residual components, r > 0 their
// redundancy.
StatusOr<Eigen::MatrixXd> LatentSandwichCovariance(const LatentLinearization& lin,
                                                   const LatentPrior& prior,
                                                   const LatentCovariance& covariance, int lag,
                                                   double components, double redundancy);

}  // namespace calib

#endif  // CALIB_SOLVERS_TIMING_LATENT_TIME_STATISTICS_H_
