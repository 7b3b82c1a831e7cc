#include <calib/core/bearing/bearing_log_io.h>
#include <calib/solvers/bearing/bearing_text.h>
#include <calib/solvers/bearing/martinelli_closed_form.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <complex>

namespace calib {
namespace {

using Complex = std::complex<double>;

// At least three distinct q (§7).
Status CheckDistinctRatios(const MartinelliEstimate& estimate, const MartinelliOptions& options) {
  std::vector<double> distinct;
  for (const MartinelliRunEstimate& run : estimate.runs) {
    const bool seen = std::any_of(distinct.begin(), distinct.end(), [&](double q) {
      return std::abs(q - run.q) < options.min_q_separation;
    });
    if (!seen) distinct.push_back(run.q);
  }
  if (distinct.size() < 3) {
    std::string qs;
    for (const MartinelliRunEstimate& run : estimate.runs) {
      qs += (qs.empty() ? "" : ", ") + RunName(run.run) + ": q = " + Num(run.q, 3);
    }
    return Status::NotObservable(
        "the closed form needs circular runs with at least 3 "
        "distinct wheel-speed ratios q = vL/vR (differing by ≥ " +
        Num(options.min_q_separation, 3) + "); found " + std::to_string(distinct.size()) +
        (qs.empty() ? "" : " (" + qs + ")"));
  }

  return Status::Ok();
}

// The per-run fits of every circular run (non-circular ones skipped when the options say so).
// Fewer than three distinct q leave the closed form undetermined whatever the circles: that is
// said before fitting them (a long run weaving about one mean ratio passes as circular, and its
// fit was most of a bearing calibration's time).
Status FitRuns(const BearingLog& log, const std::vector<std::vector<bool>>* keep,
               const MartinelliOptions& options, MartinelliEstimate* estimate) {
  std::vector<CircularRunSamples> circular;
  MartinelliEstimate ratios;
  for (size_t i = 0; i < log.runs.size(); ++i) {
    const BearingRun& run = log.runs[i];
    CALIB_ASSIGN_OR_RETURN(CircularRunSamples samples,
                           ExtractCircularRun(run, log.meta.wheel_radius_m, options,
                                              keep != nullptr ? &(*keep)[i] : nullptr));
    if (!samples.circle) {
      if (!options.skip_non_circular_runs) return Status::NotObservable(samples.not_circle);
      estimate->skipped_runs.push_back(run.id);
      continue;
    }
    ratios.runs.emplace_back();
    ratios.runs.back().run = samples.run;
    ratios.runs.back().q = samples.q;
    circular.push_back(std::move(samples));
  }
  CALIB_RETURN_IF_ERROR(CheckDistinctRatios(ratios, options));
  for (const CircularRunSamples& samples : circular) {
    CALIB_ASSIGN_OR_RETURN(const MartinelliRunEstimate fitted,
                           FitCircularRun(samples, log.meta.wheelbase_m, options));
    estimate->runs.push_back(fitted);
  }
  return Status::Ok();
}

void SolveXiDelta(MartinelliEstimate* estimate) {
  // ξ and δ from ξq = ξ − ξδ·q (eq. 11), least squares over the runs.
  Eigen::Matrix2d normal = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  // Weighted by each ξq's variance: a long run at q near 1/δ pins ξ(1 − qδ) far better than the
  // short ones, which is what makes δ precise (the residual noise floor keeps weights bounded).
  for (const MartinelliRunEstimate& run : estimate->runs) {
    const double variance =
        run.circle_covariance(0, 0) + std::pow(1e-9 * std::abs(run.xi_q_per_m), 2) + 1e-300;
    const Eigen::Vector2d row(1.0, -run.q);
    normal += row * row.transpose() / variance;
    rhs += row * run.xi_q_per_m / variance;
  }
  const Eigen::Vector2d xi_xidelta = normal.ldlt().solve(rhs);
  BearingParams& p = estimate->params;
  p.xi_per_m = xi_xidelta(0);
  p.delta = xi_xidelta(1) / xi_xidelta(0);
}

Status SolvePhiPsiEta(MartinelliEstimate* estimate) {
  BearingParams& p = estimate->params;
  // φ, ψ, η. The direction of the centre of rotation from the sensor, θC + φ + ψ in the robot
  // frame, is that of g = (−ξq cos φ, ηq − ξq sin φ)·sign(ξq); its cross product with the measured
  // direction vanishes:
  //   (1 + qδ)·(cos θC·X1 − sin θC·X2) + ξq·(sin θC·Y1 + cos θC·Y2) = 0,
  // with X = η·(cos(φ+ψ), sin(φ+ψ)), Y = (cos ψ, sin ψ): linear and homogeneous, so three runs
  // give X and Y up to a common factor, fixed by |Y| = 1 and the sign of the dot product. This is
  // §7's system ηx·Ψ1 + ηy = f_q with Ψ1 = tan(ψ − L), multiplied through by cos(ψ − L)(1 + qδ),
  // where f_q must read ξ(1 − qδ)/(1 + qδ) (the report prints it inverted).
  const int runs = static_cast<int>(estimate->runs.size());
  Eigen::MatrixXd mx(runs, 2), my(runs, 2);
  Eigen::Vector2d x, y;
  double eta_guess = 0.0, phi_guess = 0.0;
  for (int pass = 0; pass < 2; ++pass) {
    for (int i = 0; i < runs; ++i) {
      const MartinelliRunEstimate& run = estimate->runs[i];
      const double theta = run.circle.center_bearing_rad;
      const double one_plus = 1.0 + run.q * p.delta;
      const double xi_q = XiQ(p.xi_per_m, p.delta, run.q);
      // Rows scaled to unit |g| so each run weighs by its angle, not by its ξq.
      double norm = 1.0;
      if (pass > 0) {
        const double eta_q = eta_guess * one_plus;
        norm = std::sqrt(std::max(
            xi_q * xi_q + eta_q * eta_q - 2.0 * xi_q * eta_q * std::sin(phi_guess), 1e-300));
      }
      mx.row(i) << one_plus * std::cos(theta) / norm, -one_plus * std::sin(theta) / norm;
      my.row(i) << xi_q * std::sin(theta) / norm, xi_q * std::cos(theta) / norm;
    }
    const Eigen::Matrix2d pxx = mx.transpose() * mx;
    const double scale = (mx.transpose() * mx).trace() + (my.transpose() * my).trace();
    if (!(std::abs(pxx.determinant()) > 1e-12 * pxx.trace() * pxx.trace())) {
      return Status::NotObservable(
          "the runs see their centres of rotation in one direction, so η and φ cannot be "
          "separated: the sensor sits on the line of the wheel axle (φ ≈ ±90°), where η is not "
          "observable from circles, or the runs are too alike");
    }
    const Eigen::Matrix2d gain = pxx.inverse() * (mx.transpose() * my);
    const Eigen::Matrix2d schur = my.transpose() * my - (my.transpose() * mx) * gain;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(schur);
    if (!(eigen.eigenvalues()(1) > 1e-12 * scale)) {
      return Status::NotObservable("the runs do not determine ψ (degenerate geometry)");
    }
    y = eigen.eigenvectors().col(0);
    x = -gain * y;
    double sign = 0.0;
    for (int i = 0; i < runs; ++i) {
      const MartinelliRunEstimate& run = estimate->runs[i];
      const double theta = run.circle.center_bearing_rad;
      const double xi_q = XiQ(p.xi_per_m, p.delta, run.q);
      const double dot =
          -xi_q * (std::cos(theta) * y(0) - std::sin(theta) * y(1)) +
          (1.0 + run.q * p.delta) * (std::sin(theta) * x(0) + std::cos(theta) * x(1));
      sign += xi_q < 0.0 ? -dot : dot;
    }
    if (sign < 0.0) x = -x, y = -y;
    eta_guess = x.norm();
    p.psi_rad = std::atan2(y(1), y(0));
    p.phi_rad = WrapAngle(std::atan2(x(1), x(0)) - p.psi_rad);
    phi_guess = p.phi_rad;
  }
  p.eta_per_m = x.norm();
  estimate->eta_x_per_m = p.eta_per_m * std::cos(p.phi_rad);
  estimate->eta_y_per_m = p.eta_per_m * std::sin(p.phi_rad);

  return Status::Ok();
}

void CompleteRuns(MartinelliEstimate* estimate) {
  const BearingParams& p = estimate->params;
  // Per run: L on its defined branch, A0, V0 (eq. 14 at s = 0), c (eq. 21) and its S_w (eq. 26),
  // then μ0, γ0 by inverting eqs. 13 and 15.
  for (MartinelliRunEstimate& run : estimate->runs) {
    const double xi_q = run.xi_q_per_m;
    const double eta_q = EtaQ(p.eta_per_m, p.delta, run.q);
    const double xi_q_model = XiQ(p.xi_per_m, p.delta, run.q);
    const double l_model = p.psi_rad - std::atan(Psi1(p.phi_rad, eta_q, xi_q_model));
    run.l_rad = NearestModulo(run.l_rad, M_PI, l_model);
    run.l_algorithm1_rad = NearestModulo(run.l_algorithm1_rad, M_PI, l_model);
    CircleState(run.circle, 0.0, &run.a0, &run.v0);
    run.c_rad = CFromKV(run.k_per_m, run.v0, xi_q);
    const double base = 0.5 * M_PI - xi_q * run.node_m;
    for (int i = 0; i < 2; ++i) {
      const double c = (i == 0 ? 1.0 : -1.0) * base;
      run.c_candidates_rad[i] = c - M_PI * std::ceil(c / M_PI - 0.5);
    }
    // S_w: c + S_w·ξq·s_n ≡ π/2 (mod π).
    const auto miss = [&](int s_w) {
      const double e = std::fmod(run.c_rad + s_w * xi_q * run.node_m - 0.5 * M_PI, M_PI);
      return std::min(std::abs(e), M_PI - std::abs(e));
    };
    run.s_w = miss(1) <= miss(-1) ? 1 : -1;
    GammaMuFromState(run.a0, run.v0, p.phi_rad, eta_q, xi_q, &run.gamma0_rad, &run.mu0);
    run.gamma0_rad = WrapAngle(run.gamma0_rad);
    if (!std::isfinite(run.mu0) || !std::isfinite(run.gamma0_rad) || !(run.mu0 > 0.0)) {
      // Eqs. 13 and 15 are singular (cos φ = 0, ηq = 0, ...): place the landmark directly. In
      // the robot frame at s = 0 it sits at ρ·[(0, ηq/ξq) + g·r·e^{iξq·s_n}] with the centre's
      // offset from the sensor g = (−cos φ, ηq/ξq − sin φ).
      const Complex center(0.0, eta_q / xi_q);
      const Complex offset(-std::cos(p.phi_rad), eta_q / xi_q - std::sin(p.phi_rad));
      const Complex landmark =
          center + offset * run.circle.ratio * std::polar(1.0, xi_q * run.circle.node_m);
      run.mu0 = 1.0 / std::abs(landmark);
      run.gamma0_rad = WrapAngle(p.phi_rad - std::arg(-landmark));
    }
  }
}

}  // namespace

StatusOr<MartinelliEstimate> MartinelliClosedFormOf(const BearingLog& log,
                                                    const std::vector<std::vector<bool>>* keep,
                                                    const MartinelliOptions& options) {
  MartinelliEstimate estimate;
  CALIB_RETURN_IF_ERROR(FitRuns(log, keep, options, &estimate));
  CALIB_RETURN_IF_ERROR(CheckDistinctRatios(estimate, options));
  SolveXiDelta(&estimate);
  CALIB_RETURN_IF_ERROR(SolvePhiPsiEta(&estimate));
  CompleteRuns(&estimate);
  if (log.meta.initial_distance) {
    const InitialDistance& d = *log.meta.initial_distance;
    const auto run = std::find_if(estimate.runs.begin(), estimate.runs.end(),
                                  [&](const MartinelliRunEstimate& r) { return r.run == d.run; });
    if (run != estimate.runs.end()) {
      // ρ = μ0·D0 (end of §7).
      estimate.metric = MetricParams(estimate.params, run->mu0 * d.meters, log.meta.wheelbase_m);
      estimate.has_metric = true;
    }
  }
  return estimate;
}

StatusOr<MartinelliEstimate> MartinelliClosedForm(const BearingLog& log,
                                                  const MartinelliOptions& options) {
  CALIB_RETURN_IF_ERROR(ValidateBearingLog(log));
  const std::string source = log.source.empty() ? "bearing log" : log.source;
  StatusOr<MartinelliEstimate> estimate = MartinelliClosedFormOf(log, nullptr, options);
  if (!estimate.ok()) return estimate.status().Prefixed(source + ": ");
  if (log.meta.initial_distance && !estimate->has_metric) {
    return Status::NotObservable(source + ": the initial distance is given for " +
                                 RunName(log.meta.initial_distance->run) +
                                 ", which is not a circular run used by the closed form");
  }
  return estimate;
}

}  // namespace calib
