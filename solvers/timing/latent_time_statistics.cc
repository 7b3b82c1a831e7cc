#include <calib/core/timing/banded_ldlt.h>
#include <calib/solvers/common/parallel_chunks.h>
#include <calib/solvers/stats/score_test.h>
#include <calib/solvers/timing/latent_time_statistics.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <vector>

namespace calib {
namespace {

// H_ll + Λ factored, H_ll's band from `make_band`: called again (rather than copied) for the
// rare retry with a relative ridge, for round-off on near noise-free data (whitening by a floored
// noise level).
template <typename MakeBand>
StatusOr<BandedLdlt> FactorBandWithPrior(const MakeBand& make_band, const LatentPrior& prior) {
  const auto with_prior = [&] {
    Eigen::MatrixXd band = make_band();
    band.row(0) += prior.sigma.array().square().inverse().matrix().transpose();
    return band;
  };
  BandedLdlt ldlt;
  if (ldlt.Compute(with_prior())) return ldlt;
  Eigen::MatrixXd band = with_prior();
  band.row(0).array() += 1e-12 * band.row(0).cwiseAbs().maxCoeff();
  if (!ldlt.Compute(std::move(band))) {
    return Status::NotObservable("the information of the sample times is not positive definite");
  }
  return ldlt;
}

StatusOr<BandedLdlt> FactorWithPrior(const LatentLinearization& lin, const LatentPrior& prior) {
  return FactorBandWithPrior([&] { return lin.h_ll_band; }, prior);
}

// Of the three components' bands H_c (lower bands, band(d, i) = H(i + d, i)) in one pass, which
// reads each band once (the evaluation is bound by memory): xᵀH_c·x and tr(Z·H_c), Z symmetric
// and given by its lower band of the same width.
void QuadraticsAndTraces(const std::array<Eigen::MatrixXd, 3>& h, const Eigen::VectorXd& x,
                         const Eigen::MatrixXd& z, double quadratic[3], double trace[3]) {
  const Eigen::Index rows = z.rows(), n = z.cols();
  double q[3] = {0.0, 0.0, 0.0}, t[3] = {0.0, 0.0, 0.0};
  for (Eigen::Index i = 0; i < n; ++i) {
    const Eigen::Index reach = std::min(rows - 1, n - 1 - i);
    const double* zi = z.data() + i * rows;
    const double* hi[3] = {h[0].data() + i * rows, h[1].data() + i * rows, h[2].data() + i * rows};
    // The diagonal once, the entries below it twice (for the entries above).
    for (Eigen::Index d = 0; d <= reach; ++d) {
      const double weight = d == 0 ? 1.0 : 2.0;
      const double xx = weight * x(i) * x(i + d), zz = weight * zi[d];
      for (int c = 0; c < 3; ++c) q[c] += hi[c][d] * xx, t[c] += hi[c][d] * zz;
    }
  }
  for (int c = 0; c < 3; ++c) quadratic[c] = q[c], trace[c] = t[c];
}

}  // namespace

LatentPrior MakeLatentPrior(const LatentLinearization& lin, double offset_s, double sensor_sigma_s,
                            double encoder_sigma_s) {
  const Eigen::Index n = lin.latent_value.size();
  LatentPrior prior{Eigen::VectorXd::Zero(n), Eigen::VectorXd::Zero(n)};
  for (Eigen::Index i = 0; i < n; ++i) {
    prior.mean(i) = lin.latent_is_sensor[i] ? offset_s : 0.0;
    prior.sigma(i) = lin.latent_is_sensor[i] ? sensor_sigma_s : encoder_sigma_s;
  }
  return prior;
}

StatusOr<LatentEvidence> LatentEvidenceWithGradient(const LatentLinearization& lin, double offset_s,
                                                    const NoiseScales& scales, bool with_gradient) {
  const Eigen::Array3d scale = (lin.noise_sigma.array() / scales.scan.array()).square();
  LatentEvidence out;
  out.value =
      scale.matrix().dot(lin.rr_c) + 2.0 * lin.num_intervals * scales.scan.array().log().sum();
  // d/d log σ_c: the scan rows scale by σ0/σ_c, so every term in them by −2.
  for (int c = 0; c < 3; ++c)
    out.gradient(c) = -2.0 * scale(c) * lin.rr_c(c) + 2.0 * lin.num_intervals;
  if (lin.latent_value.size() == 0) return out;
  const LatentPrior prior = MakeLatentPrior(lin, offset_s, scales.sensor_s, scales.encoder_s);
  // Σ s_c H_c in one pass (the band of each evaluation is built once and factored in place).
  const auto scaled_band = [&] {
    return Eigen::MatrixXd(scale(0) * lin.h_ll_band_c[0] + scale(1) * lin.h_ll_band_c[1] +
                           scale(2) * lin.h_ll_band_c[2]);
  };
  CALIB_ASSIGN_OR_RETURN(const BandedLdlt ldlt, FactorBandWithPrior(scaled_band, prior));
  const Eigen::VectorXd b =
      scale(0) * lin.b_l_c[0] + scale(1) * lin.b_l_c[1] + scale(2) * lin.b_l_c[2];
  const Eigen::VectorXd lambda = prior.sigma.array().square().inverse();
  const Eigen::VectorXd dm = prior.mean - lin.latent_value;
  const Eigen::VectorXd u = b - lambda.cwiseProduct(dm);
  Eigen::VectorXd x = u;
  ldlt.SolveInPlace(&x);
  out.value += dm.dot(lambda.cwiseProduct(dm)) - u.dot(x) + ldlt.LogDeterminant() +
               2.0 * prior.sigma.array().log().sum();
  if (!with_gradient) return out;
  // With A = Σ s_c H_c + Λ, u = Σ s_c b_c − Λ·dm, x = A⁻¹u and Z = A⁻¹:
  //   d(−uᵀA⁻¹u) = −2xᵀdu + xᵀdA·x,  d log det A = tr(Z·dA).
  const Eigen::MatrixXd z = ldlt.InverseBand();
  double quadratic[3], trace[3];
  QuadraticsAndTraces(lin.h_ll_band_c, x, z, quadratic, trace);
  for (int c = 0; c < 3; ++c) {
    out.gradient(c) += scale(c) * (4.0 * x.dot(lin.b_l_c[c]) - 2.0 * quadratic[c] - 2.0 * trace[c]);
  }
  // d/d log σ_i of a prior: dΛ_ii = −2λ_i; the latent's departure from its prior mean is
  // −(dm_i + x_i), so the terms gather into −2λ_i[(dm_i + x_i)² + Z_ii] + 2 (EM's σ² update).
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    const double departure = dm(i) + x(i);
    const double term = -2.0 * lambda(i) * (departure * departure + z(0, i)) + 2.0;
    out.gradient(lin.latent_is_sensor[i] ? 3 : 4) += term;
  }
  return out;
}

StatusOr<double> LatentNegLogEvidence(const LatentLinearization& lin, double offset_s,
                                      const NoiseScales& scales) {
  CALIB_ASSIGN_OR_RETURN(const LatentEvidence e,
                         LatentEvidenceWithGradient(lin, offset_s, scales, false));
  return e.value;
}

namespace {

using Vector5d = Eigen::Matrix<double, 5, 1>;

NoiseScales ScalesFromLog(const Vector5d& theta) {
  NoiseScales s;
  s.scan = theta.head<3>().array().exp();
  s.sensor_s = std::exp(theta(3));
  s.encoder_s = std::exp(theta(4));
  return s;
}

// One projected Newton step's direction on the free coordinates not held at a bound: the Hessian
// by forward differences of the analytic gradient, damped until positive definite.
// The columns' gradients are independent: they run on up to `threads` threads.
template <typename Gradient>
std::optional<Vector5d> NewtonDirection(const Vector5d& theta, const Vector5d& gradient,
                                        const std::array<bool, 5>& active,
                                        const Gradient& gradient_at, int threads) {
  std::vector<int> index;
  for (int i = 0; i < 5; ++i) {
    if (active[i]) index.push_back(i);
  }
  const int m = static_cast<int>(index.size());
  if (m == 0) return std::nullopt;
  constexpr double kStep = 1e-4;
  std::vector<std::optional<Vector5d>> shifted_gradient(m);
  ParallelChunks(m, threads, 1, [&](int, size_t begin, size_t end) {
    for (size_t a = begin; a < end; ++a) {
      Vector5d shifted = theta;
      shifted(index[a]) += kStep;
      shifted_gradient[a] = gradient_at(shifted);
    }
  });
  Eigen::MatrixXd hessian(m, m);
  for (int a = 0; a < m; ++a) {
    const std::optional<Vector5d>& g = shifted_gradient[a];
    if (!g) return std::nullopt;
    for (int b = 0; b < m; ++b) hessian(b, a) = ((*g)(index[b]) - gradient(index[b])) / kStep;
  }
  hessian = 0.5 * (hessian + hessian.transpose()).eval();
  Eigen::VectorXd g(m);
  for (int a = 0; a < m; ++a) g(a) = gradient(index[a]);
  double damping = 0.0;
  for (int attempt = 0; attempt < 30; ++attempt) {
    Eigen::MatrixXd damped = hessian;
    damped.diagonal().array() += damping;
    const Eigen::LLT<Eigen::MatrixXd> llt(damped);
    if (llt.info() == Eigen::Success) {
      const Eigen::VectorXd p = -llt.solve(g);
      Vector5d direction = Vector5d::Zero();
      for (int a = 0; a < m; ++a) direction(index[a]) = p(a);
      return direction;
    }
    damping = std::max(1e-6 * hessian.diagonal().cwiseAbs().maxCoeff(), 4.0 * damping);
  }
  return std::nullopt;
}

}  // namespace

// In −2 log evidence: a likelihood ratio of 1.005.
constexpr double kEvidenceGainTolerance = 0.01;

NoiseScales MaximizeLatentEvidence(const LatentLinearization& lin, double offset_s,
                                   NoiseScales initial, const NoiseScaleFit& fit, double* gain) {
  if (gain) *gain = 0.0;
  const bool has_sensor = std::find(lin.latent_is_sensor.begin(), lin.latent_is_sensor.end(),
                                    true) != lin.latent_is_sensor.end();
  const bool has_encoder = std::find(lin.latent_is_sensor.begin(), lin.latent_is_sensor.end(),
                                     false) != lin.latent_is_sensor.end();
  Vector5d theta, lo, hi;
  std::array<bool, 5> free = {fit.scan, fit.scan, fit.scan, fit.sensor && has_sensor,
                              fit.encoder && has_encoder};
  theta << initial.scan.array().log(), std::log(std::max(initial.sensor_s, 1e-300)),
      std::log(std::max(initial.encoder_s, 1e-300));
  for (int c = 0; c < 3; ++c) lo(c) = theta(c) - std::log(8.0), hi(c) = theta(c) + std::log(8.0);
  lo.tail<2>().setConstant(std::log(fit.floor_s));
  hi.tail<2>().setConstant(std::log(fit.ceiling_s));
  for (int i = 3; i < 5; ++i) {
    if (free[i]) theta(i) = std::clamp(theta(i), lo(i), hi(i));
  }
  const auto evaluate = [&](const Vector5d& at, bool gradient) -> std::optional<LatentEvidence> {
    StatusOr<LatentEvidence> e =
        LatentEvidenceWithGradient(lin, offset_s, ScalesFromLog(at), gradient);
    if (!e.ok() || !std::isfinite(e->value)) return std::nullopt;
    return *e;
  };
  const auto gradient_at = [&](const Vector5d& at) -> std::optional<Vector5d> {
    const std::optional<LatentEvidence> e = evaluate(at, true);
    if (!e) return std::nullopt;
    return e->gradient;
  };
  std::optional<LatentEvidence> current = evaluate(theta, true);
  if (!current) return initial;
  constexpr double kEdge = 1e-9;
  double previous = current->value;
  const double start = current->value;
  for (int iteration = 0; iteration < 30; ++iteration) {
    // Coordinates at a bound whose gradient points out of the box stay there.
    std::array<bool, 5> active = free;
    for (int i = 0; i < 5; ++i) {
      if ((theta(i) <= lo(i) + kEdge && current->gradient(i) > 0.0) ||
          (theta(i) >= hi(i) - kEdge && current->gradient(i) < 0.0)) {
        active[i] = false;
      }
    }
    std::optional<Vector5d> direction =
        NewtonDirection(theta, current->gradient, active, gradient_at, fit.num_threads);
    if (!direction) break;
    // At most a factor e per step in any σ.
    const double longest = direction->cwiseAbs().maxCoeff();
    if (longest > 1.0) *direction /= longest;
    bool accepted = false;
    Vector5d moved = theta;
    for (double t = 1.0; t > 1e-3 && !accepted; t *= 0.5) {
      moved = (theta + t * *direction).cwiseMax(lo).cwiseMin(hi);
      for (int i = 0; i < 5; ++i) {
        if (!free[i]) moved(i) = theta(i);
      }
      std::optional<LatentEvidence> trial = evaluate(moved, true);
      if (trial && trial->value <= current->value + 1e-9 * std::abs(current->value)) {
        current = trial;
        accepted = true;
      }
    }
    if (!accepted) break;
    const double step_gain = previous - current->value;
    previous = current->value;
    const double change = (moved - theta).cwiseAbs().maxCoeff();
    theta = moved;
    // 0.1 % in every σ, or an evidence that no longer changes: a σ the data hardly determine
    // (a jitter heading for the floor) can otherwise creep along its flat valley for dozens of
    // steps.
    if (change < 1e-3 || step_gain < kEvidenceGainTolerance) break;
  }
  if (gain) *gain = start - current->value;
  NoiseScales out = ScalesFromLog(theta);
  if (!free[3]) out.sensor_s = initial.sensor_s;
  if (!free[4]) out.encoder_s = initial.encoder_s;
  if (!fit.scan) out.scan = initial.scan;
  return out;
}

StatusOr<LatentCovariance> MarginalLatentCovariance(const LatentLinearization& lin,
                                                    const LatentPrior& prior) {
  const int g = lin.num_globals;
  const Eigen::Index n = lin.latent_value.size();
  Eigen::MatrixXd b = lin.h_lg;
  Eigen::MatrixXd c = lin.h_gg;
  if (lin.offset_global >= 0) {
    // The prior (δ − τ)/σ couples each sensor latent with τ.
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!lin.latent_is_sensor[i]) continue;
      const double w = 1.0 / (prior.sigma(i) * prior.sigma(i));
      b(i, lin.offset_global) -= w;
      c(lin.offset_global, lin.offset_global) += w;
    }
  }
  LatentCovariance out;
  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(n, g);
  Eigen::VectorXd z = Eigen::VectorXd::Zero(n);
  if (n > 0) {
    CALIB_ASSIGN_OR_RETURN(const BandedLdlt ldlt, FactorWithPrior(lin, prior));
    x = ldlt.Solve(b);
    z = ldlt.InverseDiagonal();
    out.log_det = ldlt.LogDeterminant();
  }
  const Eigen::MatrixXd schur = c - b.transpose() * x;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt_g(schur);
  if (ldlt_g.info() != Eigen::Success || !(ldlt_g.vectorD().array() > 0.0).all()) {
    return Status::NotObservable(
        "the information matrix is singular: the log does not determine the six parameters "
        "and the timing together");
  }
  out.globals = ldlt_g.solve(Eigen::MatrixXd::Identity(g, g));
  out.latent_variance = z + ((x * out.globals).cwiseProduct(x)).rowwise().sum();
  for (Eigen::Index i = 0; i < n; ++i) {
    out.effective_latents += 1.0 - z(i) / (prior.sigma(i) * prior.sigma(i));
  }
  out.latent_gain = std::move(x);
  return out;
}

StatusOr<Eigen::MatrixXd> LatentProfileScores(const LatentLinearization& lin,
                                              const LatentPrior& prior,
                                              const LatentCovariance& covariance) {
  const Eigen::Index rows = lin.score_globals.rows(), n = lin.latent_value.size();
  if (rows == 0 || static_cast<Eigen::Index>(lin.score_latents.size()) != rows ||
      static_cast<Eigen::Index>(lin.latent_row.size()) != n || covariance.latent_gain.rows() != n) {
    return Status::Internal("the profile scores need the intervals' scores (Linearize(true))");
  }
  const Eigen::MatrixXd& x = covariance.latent_gain;
  Eigen::MatrixXd u = lin.score_globals;
  for (Eigen::Index i = 0; i < rows; ++i) {
    for (const LatentLinearization::LatentScore& l : lin.score_latents[i]) {
      if (l.latent >= 0) u.row(i) -= l.value * x.row(l.latent);
    }
  }
  // A prior ½((v − m)/σ)² adds λ(v − m) to its latent's score, and −λ(v − m) to τ's where m = τ.
  for (Eigen::Index a = 0; a < n; ++a) {
    const int row = lin.latent_row[a];
    if (row < 0 || !(prior.sigma(a) > 0.0)) continue;
    const double score = (lin.latent_value(a) - prior.mean(a)) / (prior.sigma(a) * prior.sigma(a));
    u.row(row) -= score * x.row(a);
    if (lin.latent_is_sensor[a] && lin.offset_global >= 0) u(row, lin.offset_global) -= score;
  }
  return u;
}

StatusOr<Eigen::MatrixXd> LatentSandwichCovariance(const LatentLinearization& lin,
                                                   const LatentPrior& prior,
                                                   const LatentCovariance& covariance, int lag,
                                                   double components, double redundancy) {
  if (!(redundancy > 0.0)) return Status::NotObservable("too few residuals for a covariance");
  CALIB_ASSIGN_OR_RETURN(const Eigen::MatrixXd u, LatentProfileScores(lin, prior, covariance));
  const Eigen::MatrixXd& c = covariance.globals;
  return Eigen::MatrixXd(c * LongRunCovariance(u, lag) * c * (components / redundancy));
}

}  // namespace calib
