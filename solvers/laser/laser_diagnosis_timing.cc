#include <calib/core/text_format.h>
#include <calib/solvers/diagnosis/statement.h>
#include <calib/solvers/laser/laser_diagnosis_internal.h>
#include <calib/solvers/stats/change_point.h>
#include <calib/solvers/timing/interval_jitter.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

// The timing step of the laser diagnosis: stamp_jitter is tested, confirmed and modelled before
// any physical candidate, so that the physical candidates are tested (and refitted and
// confirmed on held-out blocks) with the timing model in the base.
namespace calib::laser_diagnosis {
namespace {

std::vector<Eigen::Vector3d> Rows(const Eigen::MatrixXd& m) {
  std::vector<Eigen::Vector3d> rows(m.rows());
  for (Eigen::Index k = 0; k < m.rows(); ++k) rows[k] = m.row(k).transpose();
  return rows;
}

// −log of the Gaussian density (without the constant) of the held-out inliers' errors under
// Σ_k = diag(σ_n²) + σ_j²(g_s g_sᵀ + g_e g_eᵀ).
double HeldOutNll(const std::vector<Eigen::Vector3d>& errors,
                  const std::vector<IntervalTimeSensitivity>& g, const Eigen::Vector3d& noise,
                  double jitter_s, const std::vector<bool>& use) {
  double sum = 0.0;
  for (size_t k = 0; k < errors.size(); ++k) {
    if (!use[k]) continue;
    Eigen::Matrix3d sigma = JitterCovariance(g[k], jitter_s);
    sigma.diagonal() += noise.cwiseAbs2();
    const Eigen::LLT<Eigen::Matrix3d> llt(sigma);
    const Eigen::Vector3d z = llt.matrixL().solve(errors[k]);
    sum += 0.5 * z.squaredNorm() + llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
  }
  return sum;
}

// Held-out blocks: σ_j and σ_n estimated without each block, then the block's likelihood with the
// jitter against the same without it (σ_n re-estimated at σ_j = 0).
void CrossValidateJitter(const Context& context, const std::vector<Eigen::Vector3d>& errors,
                         const std::vector<IntervalTimeSensitivity>& g,
                         const Eigen::Vector3d& noise, const std::vector<bool>& inlier,
                         Finding* f) {
  double before = 0.0, after = 0.0;
  for (size_t fold = 0; fold < context.train_masks.size(); ++fold) {
    std::vector<bool> train(inlier.size()), test(inlier.size());
    for (size_t k = 0; k < inlier.size(); ++k) {
      train[k] = inlier[k] && context.train_masks[fold][k];
      test[k] = inlier[k] && context.test_masks[fold][k];
    }
    const IntervalJitterEstimate est = EstimateIntervalJitter(errors, g, noise, train);
    before += HeldOutNll(errors, g, est.noise_sigma_without_jitter, 0.0, test);
    after += HeldOutNll(errors, g, est.noise_sigma, est.jitter_s, test);
  }
  f->heldout_cost_before = before;
  f->heldout_cost_after = after;
  f->heldout_reduction = before != 0.0 ? (before - after) / std::abs(before) : 0.0;
}

// Refits the current model with each interval whitened by its jitter covariance at `jitter_s`.
Status ModelJitter(const Context& context, const std::vector<IntervalTimeSensitivity>& g,
                   const IntervalJitterEstimate& est, Search* search) {
  context.data.SetIntervalSqrtInformation(JitterSqrtInformation(g, est.noise_sigma, est.jitter_s));
  CALIB_ASSIGN_OR_RETURN(search->current, FitLaserEffects(context.data, search->current.model,
                                                          search->current.calibration));
  search->current_held_out.reset();
  return Status::Ok();
}

std::string JitterStatement(const Finding& f) {
  const double ms = 1e3;
  const std::string test = Format("score test z = %.1f, ", f.statistic) + PValueText(f.p_value);
  if (f.significant) {
    return Format("The boundary stamps jitter: σ = %.1f ± %.1f ms (", f.value * ms, f.stddev * ms) +
           test +
           Format(
               "; profile likelihood ratio %.1f; held-out likelihood better by %.2f %%); "
               "modelled as a variance that grows with the wheel speed at the interval ends "
               "before any physical effect was tested.",
               f.lr_statistic, 100.0 * f.heldout_reduction);
  }
  std::string text = "No stamp_jitter adopted: " + test;
  if (f.stddev > 0.0)
    text += Format("; profile estimate %.1f ± %.1f ms", f.value * ms, f.stddev * ms);
  if (f.refitted) {
    text += f.lr_p_value > f.holm_level ? "; the likelihood ratio did not confirm it"
                                        : "; the held-out blocks did not confirm it";
  }
  return text + ".";
}

}  // namespace

std::string DurationClusterNote(const std::vector<LaserInterval>& intervals) {
  // Modes of the durations at 1 ms resolution: a mode holds the durations within ±2 ms of a local
  // maximum. Stamps picked up by a clock of period Q put the durations of equal true length at
  // multiples of Q apart.
  std::vector<int> counts;
  const auto bin = [](double t) { return static_cast<int>(std::lround(t * 1e3)); };
  int lo = std::numeric_limits<int>::max(), hi = 0;
  for (const LaserInterval& in : intervals) {
    lo = std::min(lo, bin(in.duration_s));
    hi = std::max(hi, bin(in.duration_s));
  }
  if (intervals.size() < 50 || hi - lo > 100000) return "";
  counts.assign(hi - lo + 1, 0);
  for (const LaserInterval& in : intervals) ++counts[bin(in.duration_s) - lo];
  std::vector<int> modes;
  int covered = 0;
  std::vector<bool> used(counts.size(), false);
  for (int round = 0; round < 4; ++round) {
    int best = -1;
    for (size_t i = 0; i < counts.size(); ++i) {
      if (!used[i] && (best < 0 || counts[i] > counts[best])) best = static_cast<int>(i);
    }
    if (best < 0 || counts[best] < static_cast<int>(intervals.size()) / 50) break;
    for (int i = std::max(0, best - 2); i <= std::min<int>(counts.size() - 1, best + 2); ++i) {
      if (!used[i]) covered += counts[i];
      used[i] = true;
    }
    modes.push_back(best + lo);
  }
  std::sort(modes.begin(), modes.end());
  if (modes.size() < 2 || covered < 0.9 * intervals.size()) return "";
  int spacing = modes[1] - modes[0];
  for (size_t i = 1; i < modes.size(); ++i) spacing = std::min(spacing, modes[i] - modes[i - 1]);
  if (spacing < 5) return "";
  std::string list;
  for (int m : modes) list += (list.empty() ? "" : ", ") + Format("%.3f", m * 1e-3);
  return "the interval durations cluster at " + list +
         Format(" s (at least %d ms apart)", spacing) +
         ": the stamps look like pick-up times of a clock with a period of about that spacing, "
         "not sample times; stamp_jitter models that quantisation as a jitter (a uniform "
         "pick-up delay over " +
         Format("%d ms has σ = %.1f ms)", spacing, spacing / std::sqrt(12.0));
}

JitterScore JitterScoreTest(const std::vector<LaserInterval>& intervals,
                            const std::vector<Eigen::Vector3d>& errors,
                            const std::vector<IntervalTimeSensitivity>& g,
                            const Eigen::Vector3d& noise, const std::vector<bool>& inlier,
                            int hac_lag) {
  // Per boundary b: u_b = Σ h_kᵀ z_k over the intervals that end or start at b (z = e/σ_n,
  // h = g/σ_n), a_b,c = Σ h_k,c², v_b = Σ_c a_b,c. The Gaussian score of σ_j² at 0 is
  // ½Σ(u_b² − v_b); with the noise scales s_c free, E[u_b²] = Σ_c a_b,c s_c + σ_j²·v_b², so the
  // test is the t-statistic of the slope on v_b in y_b = u_b²/v_b regressed on (a_b/v_b, v_b)
  // (weights 1/v_b² make Var(y_b) constant under the null), studentised by a Bartlett long-run
  // variance (u_b, u_b+1 share an interval).
  const Eigen::Vector3d inv = noise.cwiseInverse();
  std::vector<Eigen::Vector4d> rows;
  std::vector<double> y;
  const auto add = [&](double u, const Eigen::Vector3d& a) {
    const double v = a.sum();
    if (!(v > 1e-12)) return;
    rows.push_back(Eigen::Vector4d(a(0) / v, a(1) / v, a(2) / v, v));
    y.push_back(u * u / v);
  };
  const size_t n = intervals.size();
  for (size_t k = 0; k <= n; ++k) {
    // Boundary before interval k (k = n: the end of the last one).
    const bool has_prev = k > 0 && (k == n || !intervals[k].gap_before);
    const bool has_next = k < n;
    if ((has_prev && !inlier[k - 1]) || (has_next && !inlier[k])) continue;
    double u = 0.0;
    Eigen::Vector3d a = Eigen::Vector3d::Zero();
    if (has_prev) {
      const Eigen::Vector3d h = g[k - 1].end.cwiseProduct(inv);
      u += h.dot(errors[k - 1].cwiseProduct(inv));
      a += h.cwiseAbs2();
    }
    if (has_next) {
      const Eigen::Vector3d h = g[k].start.cwiseProduct(inv);
      u += h.dot(errors[k].cwiseProduct(inv));
      a += h.cwiseAbs2();
    }
    add(u, a);
    // A gap: the boundary after the previous run is its own (its end only counted above when
    // k == n); close the previous run's last boundary separately.
    if (k > 0 && k < n && intervals[k].gap_before && inlier[k - 1]) {
      const Eigen::Vector3d h = g[k - 1].end.cwiseProduct(inv);
      add(h.dot(errors[k - 1].cwiseProduct(inv)), h.cwiseAbs2());
    }
  }
  JitterScore out;
  const Eigen::Index m = static_cast<Eigen::Index>(y.size());
  if (m < 20) return out;
  Eigen::MatrixXd x(m, 4);
  Eigen::VectorXd yv(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    x.row(i) = rows[i].transpose();
    yv(i) = y[i];
  }
  const Eigen::MatrixXd xtx = x.transpose() * x;
  const Eigen::MatrixXd bread = xtx.completeOrthogonalDecomposition().pseudoInverse();
  const Eigen::VectorXd beta = bread * x.transpose() * yv;
  const Eigen::VectorXd resid = yv - x * beta;
  Eigen::MatrixXd psi(m, 4);
  for (Eigen::Index i = 0; i < m; ++i) psi.row(i) = x.row(i) * resid(i);
  Eigen::Matrix4d meat = psi.transpose() * psi;
  for (int lag = 1; lag <= hac_lag && lag < m; ++lag) {
    const double w = 1.0 - lag / (hac_lag + 1.0);
    const Eigen::Matrix4d c = psi.topRows(m - lag).transpose() * psi.bottomRows(m - lag);
    meat += w * (c + c.transpose());
  }
  const Eigen::MatrixXd covariance = bread * meat * bread;
  const double se = std::sqrt(std::max(0.0, covariance(3, 3)));
  if (!(se > 0.0)) return out;
  out.slope = beta(3);
  out.statistic = beta(3) / se;
  out.p_value = 0.5 * std::erfc(out.statistic / std::sqrt(2.0));
  out.boundaries = static_cast<int>(m);
  return out;
}

Status TimingStep(const Context& context, Search* search, LaserDiagnosis* diagnosis) {
  Finding f;
  f.name = "stamp_jitter";
  f.unit = "s";
  f.dof = 1;
  f.concealment = std::numeric_limits<double>::quiet_NaN();
  f.absorbed = f.base_shift = f.base_shift_sigmas = LaserParamVector::Zero();
  const LaserCalibration start = search->current.calibration;
  const LaserEffectEvaluation at =
      EvaluateLaserEffects(context.data, search->current.model, start, false);
  const std::vector<Eigen::Vector3d> errors = Rows(Unwhitened(context.data, at.residual));
  std::vector<bool> inlier(errors.size());
  for (size_t k = 0; k < errors.size(); ++k) {
    inlier[k] = at.residual.row(k).squaredNorm() < kInlierChi2;
  }
  const Eigen::Vector3d noise = context.data.sqrt_information().diagonal().cwiseInverse();
  const std::vector<IntervalTimeSensitivity> g =
      IntervalTimeSensitivities(context.intervals, start);
  const JitterScore score =
      JitterScoreTest(context.intervals, errors, g, noise, inlier, context.options.hac_lag);
  f.step = 0;
  f.statistic = score.statistic;
  f.p_value = score.p_value;
  f.holm_level = context.options.alpha;  // The only timing candidate of this step.
  f.score_significant = score.p_value <= f.holm_level;
  IntervalJitterOptions jitter_options;
  jitter_options.significance = context.options.alpha;
  IntervalJitterEstimate est = EstimateIntervalJitter(errors, g, noise, inlier, jitter_options);
  f.value = est.jitter_s;
  f.stddev = est.jitter_stddev_s;
  f.one_step = Eigen::VectorXd::Constant(1, est.jitter_s);
  f.one_step_stddev = Eigen::VectorXd::Constant(1, est.jitter_stddev_s);
  if (f.score_significant) {
    f.refitted = true;
    f.lr_statistic = est.lr_statistic;
    f.lr_p_value = est.p_value;
    CrossValidateJitter(context, errors, g, noise, inlier, &f);
    if (f.lr_p_value <= f.holm_level && f.heldout_cost_after < f.heldout_cost_before) {
      CALIB_RETURN_IF_ERROR(ModelJitter(context, g, est, search));
      // Once more at the refitted calibration (the sensitivities and errors move with it).
      const LaserCalibration& now = search->current.calibration;
      const std::vector<IntervalTimeSensitivity> g2 =
          IntervalTimeSensitivities(context.intervals, now);
      LaserEffectData& data = context.data;
      data.SetIntervalSqrtInformation({});
      const std::vector<Eigen::Vector3d> errors2 = Rows(
          Unwhitened(data, EvaluateLaserEffects(data, search->current.model, now, false).residual));
      est = EstimateIntervalJitter(errors2, g2, noise, inlier, jitter_options);
      CALIB_RETURN_IF_ERROR(ModelJitter(context, g2, est, search));
      f.significant = true;
      f.value = est.jitter_s;
      f.stddev = est.jitter_stddev_s;
      f.base_shift = start.ToVector() - now.ToVector();
      f.base_shift_sigmas = ShiftInSigmas(f.base_shift, diagnosis->baseline.stddev);
      search->jitter_s = est.jitter_s;
      search->jitter_stddev_s = est.jitter_stddev_s;
      diagnosis->adopted_timing.push_back(f.name);
    }
  }
  if (context.options.progress) {
    context.options.progress(Format("timing step: stamp_jitter z %.1f, σ %.1f ms%s", f.statistic,
                                    1e3 * f.value, f.significant ? " → modelled" : ""));
  }
  f.statement = JitterStatement(f);
  diagnosis->timing_findings.push_back(f);
  // Between estimated sample times, durations at multiples of the sensor period are skipped
  // samples, not pick-up quantisation.
  if (!context.options.sample_times_estimated) {
    const std::string clusters = DurationClusterNote(context.intervals);
    if (!clusters.empty()) diagnosis->notes.push_back(clusters);
  }
  return Status::Ok();
}

}  // namespace calib::laser_diagnosis
