#include <calib/solvers/timing/interval_jitter_likelihood.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

namespace calib::jitter_internal {
namespace {

// Σ = diag(θ) + s·G, packed.
inline void Covariance(const Eigen::Vector3d& theta, double s, const double g[6], double m[6]) {
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

// Σ log x_k over positive x without a logarithm per term: binary exponents summed as integers,
// mantissas (in [1, 2)) multiplied and folded back every 32 terms.
class LogSum {
 public:
  void Add(double x) {
    if (!(x >= std::numeric_limits<double>::min()) || !(x < kInfinity)) {
      plain_ += std::log(x);
      return;
    }
    uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    exponent_ += static_cast<int64_t>(bits >> 52) - 1023;
    bits = (bits & kMantissaBits) | kExponentOfOne;
    std::memcpy(&x, &bits, sizeof bits);
    mantissa_ *= x;
    if (++count_ == 32) Fold();
  }
  double Value() const { return plain_ + std::log(mantissa_) + exponent_ * std::log(2.0); }

 private:
  static constexpr double kInfinity = std::numeric_limits<double>::infinity();
  static constexpr uint64_t kMantissaBits = (uint64_t{1} << 52) - 1;
  static constexpr uint64_t kExponentOfOne = uint64_t{1023} << 52;
  void Fold() {
    int e = 0;
    mantissa_ = std::frexp(mantissa_, &e);
    exponent_ += e;
    count_ = 0;
  }
  double plain_ = 0.0, mantissa_ = 1.0;
  int64_t exponent_ = 0;
  int count_ = 0;
};

// The score and Fisher information of the log-likelihood in φ = (θ, s = σ_j²):
// u_a = ½Σ[wᵀA_a w − tr(Σ⁻¹A_a)], I_ab = ½Σ tr(Σ⁻¹A_a Σ⁻¹A_b), w = Σ⁻¹e, A_θi = E_ii, A_s = G_k.
bool JointScore(const JitterData& data, const Eigen::Vector4d& phi, Eigen::Vector4d* score,
                Eigen::Matrix4d* fisher) {
  score->setZero();
  fisher->setZero();
  for (const JitterTerm& term : data.terms) {
    double sigma[6], packed[6];
    Covariance(phi.head<3>(), phi(3), term.gram, sigma);
    if (!(InverseOfSymmetric(sigma, packed) > 0.0)) return false;
    const auto unpack = [](const double p[6]) {
      return (Eigen::Matrix3d() << p[0], p[1], p[2], p[1], p[3], p[4], p[2], p[4], p[5]).finished();
    };
    const Eigen::Matrix3d inverse = unpack(packed), g = unpack(term.gram);
    const Eigen::Vector3d w =
        inverse * Eigen::Vector3d(term.error[0], term.error[1], term.error[2]);
    const Eigen::Matrix3d m = inverse * g;  // Σ⁻¹G.
    score->head<3>() += 0.5 * (w.cwiseAbs2() - inverse.diagonal());
    (*score)(3) += 0.5 * (w.dot(g * w) - m.trace());
    fisher->topLeftCorner<3, 3>() += 0.5 * inverse.cwiseAbs2();
    const Eigen::Vector3d cross = 0.5 * (m * inverse).diagonal();
    fisher->block<3, 1>(0, 3) += cross;
    fisher->block<1, 3>(3, 0) += cross.transpose();
    (*fisher)(3, 3) += 0.5 * (m * m).trace();
  }
  return true;
}

}  // namespace

// −½Σ[log det Σ_k + e_kᵀΣ_k⁻¹e_k] at variances θ; fills the score and Fisher information in θ.
// Packed cofactors and one logarithm per 32 intervals: this loop runs for every interval at
// every step of the searches (it was most of a calibration's time on real logs).
double LogLikelihood(const JitterData& data, const Eigen::Vector3d& theta, double jitter2,
                     Eigen::Vector3d* score, Eigen::Matrix3d* fisher) {
  double quadratic = 0.0;
  LogSum log_det;
  double u[3] = {0.0, 0.0, 0.0}, f[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  for (const JitterTerm& term : data.terms) {
    double sigma[6], inverse[6], w[3];
    Covariance(theta, jitter2, term.gram, sigma);
    const double det = InverseOfSymmetric(sigma, inverse);
    // Σ is a positive diagonal plus a positive semi-definite term, so det Σ > 0.
    if (!(det > 0.0)) return -std::numeric_limits<double>::infinity();
    MultiplySymmetric(inverse, term.error, w);
    log_det.Add(det);
    quadratic += term.error[0] * w[0] + term.error[1] * w[1] + term.error[2] * w[2];
    if (score == nullptr) continue;
    u[0] += w[0] * w[0] - inverse[0], u[1] += w[1] * w[1] - inverse[3];
    u[2] += w[2] * w[2] - inverse[5];
    for (int i = 0; i < 6; ++i) f[i] += inverse[i] * inverse[i];
  }
  if (score) *score = 0.5 * Eigen::Vector3d(u[0], u[1], u[2]);
  if (fisher) {
    *fisher << f[0], f[1], f[2], f[1], f[3], f[4], f[2], f[4], f[5];
    *fisher *= 0.5;
  }
  return -0.5 * (log_det.Value() + quadratic);
}

// max over θ of the log-likelihood at σ_j² (Fisher scoring from *theta, which it updates, until
// θ moves by less than `tolerance`, relative).
double ProfileLogLikelihood(const JitterData& data, double jitter_s, bool estimate_noise,
                            Eigen::Vector3d* theta, double tolerance) {
  const double jitter2 = jitter_s * jitter_s;
  if (!estimate_noise) return LogLikelihood(data, *theta, jitter2);
  for (int iteration = 0; iteration < 100; ++iteration) {
    Eigen::Vector3d score;
    Eigen::Matrix3d fisher;
    LogLikelihood(data, *theta, jitter2, &score, &fisher);
    const Eigen::Vector3d step = fisher.ldlt().solve(score);
    const Eigen::Vector3d next = (*theta + step).cwiseMax(*theta / 10.0).cwiseMax(kMinVariance);
    const double change = ((next - *theta).cwiseQuotient(*theta)).cwiseAbs().maxCoeff();
    *theta = next;
    if (!(change > tolerance)) break;
  }
  return LogLikelihood(data, *theta, jitter2);
}

// Fisher scoring jointly in (θ, σ_j²) from (*theta, *jitter_s): the profile's maximum in a few
// passes instead of a search along σ_j with a scoring at every point. False, leaving the outputs,
// when it does not settle at a σ_j strictly within (lo, hi) (a maximum on the boundary σ_j = 0 or
// beyond the bracket: the search decides then).
bool JointMaximum(const JitterData& data, double lo, double hi, Eigen::Vector3d* theta,
                  double* jitter_s) {
  Eigen::Vector4d phi;
  phi << *theta, *jitter_s * *jitter_s;
  for (int iteration = 0; iteration < 50; ++iteration) {
    Eigen::Vector4d score;
    Eigen::Matrix4d fisher;
    if (!JointScore(data, phi, &score, &fisher)) return false;
    const Eigen::LDLT<Eigen::Matrix4d> ldlt(fisher);
    if (ldlt.info() != Eigen::Success) return false;
    // As the profile's scoring: no variance falls by more than 10× in a step.
    const Eigen::Vector4d next =
        (phi + ldlt.solve(score)).cwiseMax(phi / 10.0).cwiseMax(kMinVariance);
    if (!next.allFinite()) return false;
    const double change = ((next - phi).cwiseQuotient(phi)).cwiseAbs().maxCoeff();
    phi = next;
    const double jitter = std::sqrt(phi(3));
    if (jitter < lo / 10.0 || jitter > 10.0 * hi) return false;
    if (change > 1e-10) continue;
    if (!(jitter > lo && jitter < hi)) return false;
    *theta = phi.head<3>();
    *jitter_s = jitter;
    return true;
  }
  return false;
}

}  // namespace calib::jitter_internal
