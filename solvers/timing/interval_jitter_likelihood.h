#ifndef CALIB_SOLVERS_TIMING_INTERVAL_JITTER_LIKELIHOOD_H_
#define CALIB_SOLVERS_TIMING_INTERVAL_JITTER_LIKELIHOOD_H_

#include <Eigen/Core>
#include <vector>

// The likelihood of the interval-jitter model (interval_jitter.h) and its maximization in the
// noise variances θ and σ_j²: the inner loops of EstimateIntervalJitter.
namespace calib::jitter_internal {

// Σ_k = diag(θ) + σ_j²·G_k over the inliers, and the profile likelihood's pieces, one column per
// entry (the loops over them run on SIMD packets). Symmetric 3×3 matrices are packed as
// (00, 01, 02, 11, 12, 22).
struct JitterData {
  // Appends an interval: its error e_k and G_k = g_s g_sᵀ + g_e g_eᵀ, packed.
  void Add(const double error_k[3], const double gram_k[6]);
  void Reserve(size_t n);
  size_t size() const { return error[0].size(); }
  std::vector<double> error[3];
  std::vector<double> gram[6];
};

// Σ = diag(θ) + s·G, packed.
inline void PackedCovariance(const Eigen::Vector3d& theta, double s, const double g[6],
                             double m[6]) {
  m[0] = theta(0) + s * g[0], m[1] = s * g[1], m[2] = s * g[2];
  m[3] = theta(1) + s * g[3], m[4] = s * g[4], m[5] = theta(2) + s * g[5];
}

// The inverse of a packed symmetric 3×3 matrix by cofactors; returns the determinant (the
// inverse is meaningless unless it is > 0).
inline double InverseOfSymmetric(const double m[6], double inverse[6]) {
  const double c00 = m[3] * m[5] - m[4] * m[4], c01 = m[2] * m[4] - m[1] * m[5],
               c02 = m[1] * m[4] - m[2] * m[3];
  const double det = m[0] * c00 + m[1] * c01 + m[2] * c02;
  const double r = 1.0 / det;
  inverse[0] = c00 * r, inverse[1] = c01 * r, inverse[2] = c02 * r;
  inverse[3] = (m[0] * m[5] - m[2] * m[2]) * r;
  inverse[4] = (m[1] * m[2] - m[0] * m[4]) * r;
  inverse[5] = (m[0] * m[3] - m[1] * m[1]) * r;
  return det;
}

// y = M·x for a packed symmetric M.
inline void MultiplySymmetric(const double m[6], const double x[3], double y[3]) {
  y[0] = m[0] * x[0] + m[1] * x[1] + m[2] * x[2];
  y[1] = m[1] * x[0] + m[3] * x[1] + m[4] * x[2];
  y[2] = m[2] * x[0] + m[4] * x[1] + m[5] * x[2];
}

// Floor of the noise variances: σ = 1e-12 m or rad, as RobustNoiseSigma.
constexpr double kMinVariance = 1e-24;

// A grid point's profile only ranks it among the others: θ to 1e-3 leaves its value within
// about N·1e-6 of the maximum (the error is quadratic), far below the grid's differences (a grid
// step moves the likelihood by units to hundreds on the real sets). The joint scoring that
// follows starts there and settles to 1e-10.
constexpr double kGridTolerance = 1e-3;

// −½Σ[log det Σ_k + e_kᵀΣ_k⁻¹e_k] at variances θ; fills the score and Fisher information in θ.
double LogLikelihood(const JitterData& data, const Eigen::Vector3d& theta, double jitter2,
                     Eigen::Vector3d* score = nullptr, Eigen::Matrix3d* fisher = nullptr);

// max over θ of the log-likelihood at σ_j² (Fisher scoring from *theta, which it updates, until
// the next step would move θ by less than `tolerance`, relative: θ and the value are then those
// of the last pass, without the step).
double ProfileLogLikelihood(const JitterData& data, double jitter_s, bool estimate_noise,
                            Eigen::Vector3d* theta, double tolerance = 1e-10);

// Fisher scoring, then Newton, jointly in (θ, σ_j²) from (*theta, *jitter_s): the profile's
// maximum in a few passes instead of a search along σ_j with a scoring at every point. False,
// leaving the outputs, when it does not settle at a σ_j strictly within (lo, hi) (a maximum on the
// boundary σ_j = 0 or beyond the bracket: the search decides then). *information (when given)
// receives the observed information in (θ, σ_j²) of the last step, at the maximum to 1e-10, or
// zero when that step was not Newton's.
bool JointMaximum(const JitterData& data, double lo, double hi, Eigen::Vector3d* theta,
                  double* jitter_s, Eigen::Matrix4d* information = nullptr);

// A start for the search: σ_j from least squares of the squared errors on their expectation,
// e_{k,i}² ≈ θ_i + σ_j²·G_k,ii (one pass); 0 when that σ_j² is not positive by `min_t` standard
// errors (of the regression's scatter).
double MomentJitter(const JitterData& data, double min_t = 3.0);

}  // namespace calib::jitter_internal

#endif  // CALIB_SOLVERS_TIMING_INTERVAL_JITTER_LIKELIHOOD_H_
