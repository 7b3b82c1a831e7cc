#include <calib/solvers/common/parallel_chunks.h>
#include <calib/solvers/timing/interval_jitter_likelihood.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

namespace calib::jitter_internal {

void JitterData::Add(const double error_k[3], const double gram_k[6]) {
  for (int i = 0; i < 3; ++i) error[i].push_back(error_k[i]);
  for (int i = 0; i < 6; ++i) gram[i].push_back(gram_k[i]);
}

void JitterData::Reserve(size_t n) {
  for (std::vector<double>& column : error) column.reserve(n);
  for (std::vector<double>& column : gram) column.reserve(n);
}

namespace {

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

// The joint score's terms are taken in chunks whose columns stay in the first-level cache;
// Eigen's array expressions run them on SIMD packets (twice as fast as a term at a time).
constexpr int kChunk = 128;
using Column = Eigen::Array<double, Eigen::Dynamic, 1, 0, kChunk, 1>;

// One chunk's errors e_k, Σ_k⁻¹ (packed, by cofactors), det Σ_k and w_k = Σ_k⁻¹e_k, at
// Σ_k = diag(θ) + s·G_k.
struct Chunk {
  // False when some det Σ_k is not > 0 (Σ is a positive diagonal plus a positive semi-definite
  // term, so only a broken θ or s gives that).
  bool Compute(const JitterData& data, size_t begin, Eigen::Index n, const Eigen::Vector3d& theta,
               double s) {
    const auto column = [&](const std::vector<double>& v) {
      return Eigen::Map<const Eigen::ArrayXd>(v.data() + begin, n);
    };
    for (int i = 0; i < 3; ++i) e[i] = column(data.error[i]);
    const Column m0 = theta(0) + s * column(data.gram[0]), m1 = s * column(data.gram[1]),
                 m2 = s * column(data.gram[2]), m3 = theta(1) + s * column(data.gram[3]),
                 m4 = s * column(data.gram[4]), m5 = theta(2) + s * column(data.gram[5]);
    const Column c00 = m3 * m5 - m4.square(), c01 = m2 * m4 - m1 * m5, c02 = m1 * m4 - m2 * m3;
    det = m0 * c00 + m1 * c01 + m2 * c02;
    if (!(det > 0.0).all()) return false;
    const Column r = det.inverse();
    inverse[0] = c00 * r, inverse[1] = c01 * r, inverse[2] = c02 * r;
    inverse[3] = (m0 * m5 - m2.square()) * r;
    inverse[4] = (m1 * m2 - m0 * m4) * r;
    inverse[5] = (m0 * m3 - m1.square()) * r;
    w[0] = inverse[0] * e[0] + inverse[1] * e[1] + inverse[2] * e[2];
    w[1] = inverse[1] * e[0] + inverse[3] * e[1] + inverse[4] * e[2];
    w[2] = inverse[2] * e[0] + inverse[4] * e[1] + inverse[5] * e[2];
    return true;
  }
  // Entry (a, b) of a packed symmetric matrix.
  static constexpr int kPacked[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  Column e[3], inverse[6], det, w[3];
};

// Runs `f` on each chunk of the terms; false as soon as a chunk's Σ is not positive definite.
template <typename F>
bool ForEachChunk(const JitterData& data, const Eigen::Vector3d& theta, double s, const F& f) {
  Chunk chunk;
  const size_t n = data.size();
  for (size_t begin = 0; begin < n; begin += kChunk) {
    const Eigen::Index length = static_cast<Eigen::Index>(std::min<size_t>(kChunk, n - begin));
    if (!chunk.Compute(data, begin, length, theta, s)) return false;
    f(chunk, begin, length);
  }
  return true;
}

// The score and Fisher information of the log-likelihood in φ = (θ, s = σ_j²):
// u_a = ½Σ[wᵀA_a w − tr(Σ⁻¹A_a)], I_ab = ½Σ tr(Σ⁻¹A_a Σ⁻¹A_b), w = Σ⁻¹e, A_θi = E_ii, A_s = G_k.
// With M = Σ⁻¹G: I_θi,s = ½(MΣ⁻¹)_ii, I_ss = ½tr(M²), u_s = ½[wᵀGw − tr M].
// When `observed` is given, also the observed information −∂²ℓ = Q − I with
// Q_ab = Σ wᵀA_aΣ⁻¹A_b w: Q_θiθj = w_i(Σ⁻¹)_ij w_j, Q_θi,s = w_i v_i, Q_ss = (Gw)ᵀv, v = Σ⁻¹Gw.
bool JointScore(const JitterData& data, const Eigen::Vector4d& phi, Eigen::Vector4d* score,
                Eigen::Matrix4d* fisher, Eigen::Matrix4d* observed = nullptr) {
  constexpr auto& p = Chunk::kPacked;
  Eigen::Vector4d u = Eigen::Vector4d::Zero();
  Eigen::Matrix4d f = Eigen::Matrix4d::Zero(), q = Eigen::Matrix4d::Zero();
  const bool ok =
      ForEachChunk(data, phi.head<3>(), phi(3), [&](const Chunk& c, size_t begin, Eigen::Index n) {
        const auto g = [&](int a, int b) {
          return Eigen::Map<const Eigen::ArrayXd>(data.gram[p[a][b]].data() + begin, n);
        };
        Column m[3][3];
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b < 3; ++b) {
            m[a][b] = c.inverse[p[a][0]] * g(0, b) + c.inverse[p[a][1]] * g(1, b) +
                      c.inverse[p[a][2]] * g(2, b);
          }
        }
        Column gw[3];
        for (int a = 0; a < 3; ++a) gw[a] = g(a, 0) * c.w[0] + g(a, 1) * c.w[1] + g(a, 2) * c.w[2];
        for (int a = 0; a < 3; ++a) {
          u(a) += (c.w[a].square() - c.inverse[p[a][a]]).sum();
          f(a, 3) += (m[a][0] * c.inverse[p[0][a]] + m[a][1] * c.inverse[p[1][a]] +
                      m[a][2] * c.inverse[p[2][a]])
                         .sum();
          for (int b = a; b < 3; ++b) f(a, b) += c.inverse[p[a][b]].square().sum();
        }
        u(3) +=
            (c.w[0] * gw[0] + c.w[1] * gw[1] + c.w[2] * gw[2] - m[0][0] - m[1][1] - m[2][2]).sum();
        Column trace_m2 = m[0][0].square() + m[1][1].square() + m[2][2].square();
        trace_m2 += 2.0 * (m[0][1] * m[1][0] + m[0][2] * m[2][0] + m[1][2] * m[2][1]);
        f(3, 3) += trace_m2.sum();
        if (observed == nullptr) return;
        Column v[3];
        for (int a = 0; a < 3; ++a) {
          v[a] =
              c.inverse[p[a][0]] * gw[0] + c.inverse[p[a][1]] * gw[1] + c.inverse[p[a][2]] * gw[2];
        }
        for (int a = 0; a < 3; ++a) {
          for (int b = a; b < 3; ++b) q(a, b) += (c.w[a] * c.inverse[p[a][b]] * c.w[b]).sum();
          q(a, 3) += (c.w[a] * v[a]).sum();
        }
        q(3, 3) += (gw[0] * v[0] + gw[1] * v[1] + gw[2] * v[2]).sum();
      });
  if (!ok) return false;
  *score = 0.5 * u;
  const Eigen::Matrix4d symmetric = f.selfadjointView<Eigen::Upper>();
  *fisher = 0.5 * symmetric;
  if (observed != nullptr) {
    const Eigen::Matrix4d q_full = q.selfadjointView<Eigen::Upper>();
    *observed = q_full - *fisher;
  }
  return true;
}

}  // namespace

namespace {

// LogLikelihood's sums over the terms [begin, end): log det Σ_k and e_kᵀΣ_k⁻¹e_k, and with
// `with_score` the score's and the Fisher information's (packed); ok false when some det Σ_k is
// not > 0. Packed cofactors and one logarithm per 32 intervals, a term at a time (faster here than
// the chunks' SIMD packets, whose temporaries cost more than this loop's few operations).
struct LikelihoodSums {
  double quadratic = 0.0, log_det = 0.0;
  double u[3] = {0.0, 0.0, 0.0}, f[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  bool ok = true;
  void Add(const LikelihoodSums& o) {
    quadratic += o.quadratic, log_det += o.log_det, ok = ok && o.ok;
    for (int i = 0; i < 3; ++i) u[i] += o.u[i];
    for (int i = 0; i < 6; ++i) f[i] += o.f[i];
  }
};

LikelihoodSums LikelihoodRange(const JitterData& data, const Eigen::Vector3d& theta, double jitter2,
                               bool with_score, size_t begin, size_t end) {
  LikelihoodSums s;
  LogSum log_det;
  for (size_t k = begin; k < end; ++k) {
    const double error[3] = {data.error[0][k], data.error[1][k], data.error[2][k]};
    double gram[6], sigma[6], inverse[6], w[3];
    for (int i = 0; i < 6; ++i) gram[i] = data.gram[i][k];
    PackedCovariance(theta, jitter2, gram, sigma);
    const double det = InverseOfSymmetric(sigma, inverse);
    // Σ is a positive diagonal plus a positive semi-definite term, so det Σ > 0.
    if (!(det > 0.0)) {
      s.ok = false;
      return s;
    }
    MultiplySymmetric(inverse, error, w);
    log_det.Add(det);
    s.quadratic += error[0] * w[0] + error[1] * w[1] + error[2] * w[2];
    if (!with_score) continue;
    s.u[0] += w[0] * w[0] - inverse[0], s.u[1] += w[1] * w[1] - inverse[3];
    s.u[2] += w[2] * w[2] - inverse[5];
    for (int i = 0; i < 6; ++i) s.f[i] += inverse[i] * inverse[i];
  }
  s.log_det = log_det.Value();
  return s;
}

// From this many terms on (a million-interval log's 2 % sample), the sums run in chunks of at
// least kMinLikelihoodChunk on two threads; below, in one pass in order.
constexpr size_t kParallelLikelihoodTerms = 8192;
constexpr size_t kMinLikelihoodChunk = 4096;

}  // namespace

// −½Σ[log det Σ_k + e_kᵀΣ_k⁻¹e_k] at variances θ; fills the score and Fisher information in θ.
double LogLikelihood(const JitterData& data, const Eigen::Vector3d& theta, double jitter2,
                     Eigen::Vector3d* score, Eigen::Matrix3d* fisher) {
  const size_t n = data.size();
  const bool with_score = score != nullptr;
  LikelihoodSums sums;
  if (n < kParallelLikelihoodTerms) {
    sums = LikelihoodRange(data, theta, jitter2, with_score, 0, n);
  } else {
    std::vector<LikelihoodSums> chunks(SplitCount(n, kMinLikelihoodChunk));
    ParallelSplit(n, 2, kMinLikelihoodChunk, [&](size_t chunk, size_t begin, size_t end) {
      chunks[chunk] = LikelihoodRange(data, theta, jitter2, with_score, begin, end);
    });
    for (const LikelihoodSums& chunk : chunks) sums.Add(chunk);
  }
  if (!sums.ok) return -std::numeric_limits<double>::infinity();
  const double* u = sums.u;
  const double* f = sums.f;
  if (score) *score = 0.5 * Eigen::Vector3d(u[0], u[1], u[2]);
  if (fisher) {
    *fisher << f[0], f[1], f[2], f[1], f[3], f[4], f[2], f[4], f[5];
    *fisher *= 0.5;
  }
  return -0.5 * (sums.log_det + sums.quadratic);
}

// max over θ of the log-likelihood at σ_j² (Fisher scoring from *theta, which it updates, until
// θ moves by less than `tolerance`, relative). Without jitter Σ_k = diag(θ): the maximum is at
// the mean squared errors, in one pass.
double ProfileLogLikelihood(const JitterData& data, double jitter_s, bool estimate_noise,
                            Eigen::Vector3d* theta, double tolerance) {
  const double jitter2 = jitter_s * jitter_s;
  if (!estimate_noise) return LogLikelihood(data, *theta, jitter2);
  if (jitter2 == 0.0 && data.size() > 0) {
    for (int i = 0; i < 3; ++i) {
      double sum = 0.0;
      for (const double e : data.error[i]) sum += e * e;
      (*theta)(i) = std::max(sum / static_cast<double>(data.size()), kMinVariance);
    }
    return LogLikelihood(data, *theta, 0.0);
  }
  int held[3] = {0, 0, 0};  // Steps in a row that the 10× limit held back, per variance.
  for (int iteration = 0; iteration < 100; ++iteration) {
    Eigen::Vector3d score;
    Eigen::Matrix3d fisher;
    const double value = LogLikelihood(data, *theta, jitter2, &score, &fisher);
    const Eigen::Vector3d step = fisher.ldlt().solve(score);
    Eigen::Vector3d next = (*theta + step).cwiseMax(*theta / 10.0).cwiseMax(kMinVariance);
    // A variance the jitter explains entirely falls to the floor 10× a step (18 passes from 1e-6);
    // held back three times in a row, it goes there at once (a maximum above, if any, is one
    // scoring step back up: the likelihood is flat so far below σ_j²·G).
    for (int i = 0; i < 3; ++i) {
      held[i] = (*theta)(i) + step(i) < (*theta)(i) / 10.0 ? held[i] + 1 : 0;
      if (held[i] >= 3) next(i) = kMinVariance;
    }
    const double change = ((next - *theta).cwiseQuotient(*theta)).cwiseAbs().maxCoeff();
    // Settled: θ is within `tolerance` of the maximum, and its value is at hand (no extra pass).
    if (!(change > tolerance) && std::isfinite(value)) return value;
    *theta = next;
    if (!(change > tolerance)) break;
  }
  return LogLikelihood(data, *theta, jitter2);
}

// Fisher scoring, then Newton, jointly in (θ, σ_j²) from (*theta, *jitter_s): the profile's
// maximum in a few passes instead of a search along σ_j with a scoring at every point. False,
// leaving the outputs, when it does not settle at a σ_j strictly within (lo, hi) (a maximum on the
// boundary σ_j = 0 or beyond the bracket: the search decides then).
bool JointMaximum(const JitterData& data, double lo, double hi, Eigen::Vector3d* theta,
                  double* jitter_s, Eigen::Matrix4d* information) {
  Eigen::Vector4d phi;
  phi << *theta, *jitter_s * *jitter_s;
  // Fisher scoring converges linearly here (about 12× a pass); near the maximum, where the
  // observed information is positive definite, Newton steps take over (quadratically).
  constexpr double kNewtonBelow = 1e-2, kNewtonSettled = 1e-6;
  double change = 1.0;
  for (int iteration = 0; iteration < 50; ++iteration) {
    Eigen::Vector4d score;
    Eigen::Matrix4d fisher, observed;
    const bool newton = change < kNewtonBelow;
    if (!JointScore(data, phi, &score, &fisher, newton ? &observed : nullptr)) return false;
    Eigen::LDLT<Eigen::Matrix4d> ldlt;
    if (newton) ldlt.compute(observed);
    bool observed_used = newton;
    if (!newton || ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) {
      observed_used = false;
      ldlt.compute(fisher);
      if (ldlt.info() != Eigen::Success) return false;
    }
    const Eigen::Vector4d step = ldlt.solve(score);
    // As the profile's scoring: no variance falls by more than 10× in a step.
    const Eigen::Vector4d next = (phi + step).cwiseMax(phi / 10.0).cwiseMax(kMinVariance);
    if (!next.allFinite()) return false;
    change = ((next - phi).cwiseQuotient(phi)).cwiseAbs().maxCoeff();
    phi = next;
    const double jitter = std::sqrt(phi(3));
    if (jitter < lo / 10.0 || jitter > 10.0 * hi) return false;
    // Settled when a step moves φ by 1e-10 (relative), or by 1e-6 under Newton's quadratic
    // convergence: what is left then is of the order of its square (one pass fewer).
    if (change > 1e-10 && !(observed_used && change < kNewtonSettled)) continue;
    if (!(jitter > lo && jitter < hi)) return false;
    *theta = phi.head<3>();
    *jitter_s = jitter;
    if (information != nullptr) {
      *information = observed_used ? observed : Eigen::Matrix4d::Zero().eval();
    }
    return true;
  }
  return false;
}

double MomentJitter(const JitterData& data, double min_t) {
  // Unknowns (θ_x, θ_y, θ_θ, σ_j²); one equation per interval and component.
  constexpr int kDiagonal[3] = {0, 3, 5};  // G_ii in the packed layout.
  Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
  Eigen::Vector4d right = Eigen::Vector4d::Zero();
  double squares = 0.0;
  for (size_t k = 0; k < data.size(); ++k) {
    for (int i = 0; i < 3; ++i) {
      const double g = data.gram[kDiagonal[i]][k], y = data.error[i][k] * data.error[i][k];
      normal(i, i) += 1.0, normal(i, 3) += g, normal(3, 3) += g * g;
      right(i) += y, right(3) += g * y;
      squares += y * y;
    }
  }
  normal.bottomLeftCorner<1, 3>() = normal.topRightCorner<3, 1>().transpose();
  const Eigen::LDLT<Eigen::Matrix4d> ldlt(normal);
  const double equations = 3.0 * static_cast<double>(data.size());
  if (equations <= 4.0 || ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) {
    return 0.0;
  }
  const Eigen::Vector4d x = ldlt.solve(right);
  const double scatter = std::max(0.0, (squares - x.dot(right)) / (equations - 4.0));
  const double variance = scatter * ldlt.solve(Eigen::Vector4d::UnitW())(3);
  if (!(x(3) > 0.0) || !(x(3) > min_t * std::sqrt(variance))) return 0.0;
  return std::sqrt(x(3));
}

}  // namespace calib::jitter_internal
