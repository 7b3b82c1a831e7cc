#include <calib/core/timing/banded_ldlt.h>
#include <calib/solvers/timing/latent_time_statistics.h>

#include <algorithm>
#include <cmath>
#include <functional>

namespace calib {
namespace {

StatusOr<BandedLdlt> FactorWithPrior(const LatentLinearization& lin, const LatentPrior& prior) {
  Eigen::MatrixXd band = lin.h_ll_band;
  band.row(0) += prior.sigma.array().square().inverse().matrix().transpose();
  BandedLdlt ldlt;
  if (ldlt.Compute(band)) return ldlt;
  // Round-off on near noise-free data (whitening by a floored noise level): a relative ridge.
  band.row(0).array() += 1e-12 * band.row(0).cwiseAbs().maxCoeff();
  if (!ldlt.Compute(std::move(band))) {
    return Status::NotObservable("the information of the sample times is not positive definite");
  }
  return ldlt;
}

// Minimises f over log σ in [log lo, log hi]: a grid of 9, then golden section around the best.
double MinimizeLog(const std::function<double(double)>& f, double lo, double hi) {
  const double a = std::log(lo), b = std::log(hi);
  constexpr int kGrid = 9;
  int best = 0;
  double best_value = INFINITY;
  for (int i = 0; i < kGrid; ++i) {
    const double value = f(std::exp(a + (b - a) * i / (kGrid - 1)));
    if (value < best_value) best_value = value, best = i;
  }
  double left = a + (b - a) * std::max(0, best - 1) / (kGrid - 1);
  double right = a + (b - a) * std::min(kGrid - 1, best + 1) / (kGrid - 1);
  const double ratio = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = right - ratio * (right - left), x2 = left + ratio * (right - left);
  double f1 = f(std::exp(x1)), f2 = f(std::exp(x2));
  for (int i = 0; i < 15; ++i) {
    if (f1 < f2) {
      right = x2, x2 = x1, f2 = f1;
      x1 = right - ratio * (right - left), f1 = f(std::exp(x1));
    } else {
      left = x1, x1 = x2, f1 = f2;
      x2 = left + ratio * (right - left), f2 = f(std::exp(x2));
    }
  }
  const double x = f1 < f2 ? x1 : x2;
  return std::min(f1, f2) <= best_value ? std::exp(x) : std::exp(a + (b - a) * best / (kGrid - 1));
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

StatusOr<double> LatentNegLogEvidence(const LatentLinearization& lin, double offset_s,
                                      const NoiseScales& scales) {
  const Eigen::Array3d scale = (lin.noise_sigma.array() / scales.scan.array()).square();
  double value =
      scale.matrix().dot(lin.rr_c) + 2.0 * lin.num_intervals * scales.scan.array().log().sum();
  if (lin.latent_value.size() == 0) return value;
  const LatentPrior prior = MakeLatentPrior(lin, offset_s, scales.sensor_s, scales.encoder_s);
  LatentLinearization scaled;
  scaled.h_ll_band = scale(0) * lin.h_ll_band_c[0];
  Eigen::VectorXd b = scale(0) * lin.b_l_c[0];
  for (int c = 1; c < 3; ++c) {
    scaled.h_ll_band += scale(c) * lin.h_ll_band_c[c];
    b += scale(c) * lin.b_l_c[c];
  }
  CALIB_ASSIGN_OR_RETURN(const BandedLdlt ldlt, FactorWithPrior(scaled, prior));
  const Eigen::VectorXd lambda = prior.sigma.array().square().inverse();
  const Eigen::VectorXd dm = prior.mean - lin.latent_value;
  const Eigen::VectorXd u = b - lambda.cwiseProduct(dm);
  value += dm.dot(lambda.cwiseProduct(dm)) - u.dot(ldlt.Solve(u).col(0));
  return value + ldlt.LogDeterminant() + 2.0 * prior.sigma.array().log().sum();
}

NoiseScales MaximizeLatentEvidence(const LatentLinearization& lin, double offset_s,
                                   NoiseScales initial, const NoiseScaleFit& fit) {
  NoiseScales s = initial;
  const auto evidence = [&](const NoiseScales& trial) {
    const StatusOr<double> value = LatentNegLogEvidence(lin, offset_s, trial);
    return value.ok() ? *value : INFINITY;
  };
  const bool has_sensor = std::find(lin.latent_is_sensor.begin(), lin.latent_is_sensor.end(),
                                    true) != lin.latent_is_sensor.end();
  const bool has_encoder = std::find(lin.latent_is_sensor.begin(), lin.latent_is_sensor.end(),
                                     false) != lin.latent_is_sensor.end();
  // One coordinate: the scale `value` points at (inside s) over [lo, hi].
  const auto search = [&](double* value, double lo, double hi) {
    *value = MinimizeLog(
        [&](double x) {
          const double kept = *value;
          *value = x;
          const double e = evidence(s);
          *value = kept;
          return e;
        },
        lo, hi);
  };
  for (int sweep = 0; sweep < 2; ++sweep) {
    for (int c = 0; c < 3 && fit.scan; ++c) search(&s.scan(c), s.scan(c) / 8.0, s.scan(c) * 8.0);
    if (fit.sensor && has_sensor) search(&s.sensor_s, fit.floor_s, fit.ceiling_s);
    if (fit.encoder && has_encoder) search(&s.encoder_s, fit.floor_s, fit.ceiling_s);
  }
  return s;
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
  return out;
}

}  // namespace calib
