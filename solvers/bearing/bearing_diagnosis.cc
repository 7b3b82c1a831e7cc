#include <calib/solvers/bearing/bearing_diagnosis.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <tuple>
#include <utility>

#include <calib/solvers/common/robust_loss.h>
#include <calib/solvers/stats/score_test.h>

namespace calib {
namespace {

constexpr double kInlierChi2 = 10.83;  // χ²₁ at 99.9 %, as CalibrateBearing.
// Relative efficient information below which τ counts as absorbed by the base unknowns.
constexpr double kConfoundedInformation = 1e-6;
constexpr double kDegrees = 180.0 / M_PI;

std::string Format(const char* format, double a, double b = 0.0, double c = 0.0) {
  char text[160];
  std::snprintf(text, sizeof(text), format, a, b, c);
  return text;
}

// Display: angles in degrees, η and ξ in 1/m, δ unitless.
double ParamScale(int i) { return i == kBearingPhi || i == kBearingPsi ? kDegrees : 1.0; }
const char* ParamUnit(int i) {
  return i == kBearingPhi || i == kBearingPsi ? "°" : (i == kBearingDelta ? "" : " 1/m");
}

using ProblemPtr = std::unique_ptr<BearingProblem>;

struct Model {
  bool time_offset = false;
  double time_offset_s = 0.0;
  bool fix_time_offset = false;
};

ProblemPtr MakeProblem(const BearingLog& log, const BearingParams& params,
                       const std::vector<std::vector<Pose2d>>& poses, const BearingNoise& noise,
                       BearingAdjustmentOptions adjustment, const Model& model,
                       const std::vector<std::vector<bool>>& use_bearing = {}) {
  adjustment.model_time_offset = model.time_offset;
  adjustment.time_offset_s = model.time_offset_s;
  adjustment.fix_time_offset = model.fix_time_offset;
  adjustment.use_bearing = use_bearing;
  return std::make_unique<BearingProblem>(log, params, poses, noise, adjustment);
}

std::vector<std::vector<bool>> Inliers(const BearingProblem& problem) {
  const double cut = std::sqrt(kInlierChi2) * problem.noise().bearing_sigma_rad;
  std::vector<std::vector<bool>> inlier;
  for (const auto& run : problem.BearingErrors()) {
    std::vector<bool> flags;
    for (double e : run) flags.push_back(std::abs(e) <= cut);
    inlier.push_back(flags);
  }
  return inlier;
}

// RMS of the inlier errors (rad) and their count.
std::pair<double, int> InlierRms(const std::vector<std::vector<double>>& errors,
                                 const std::vector<std::vector<bool>>& inlier) {
  double sum = 0.0;
  int count = 0;
  for (size_t i = 0; i < errors.size(); ++i) {
    for (size_t j = 0; j < errors[i].size(); ++j) {
      if (!inlier[i][j]) continue;
      sum += errors[i][j] * errors[i][j];
      ++count;
    }
  }
  return {count > 0 ? std::sqrt(sum / count) : 0.0, count};
}

// Per bearing (in log order, runs concatenated): what the location and the plots need.
struct BearingSeries {
  std::vector<double> t_s;     // From the log start.
  std::vector<double> speed;   // v (m/s, nominal wheel radius, gauge δR = 1).
  std::vector<double> turn;    // ω (rad/s).
  std::vector<double> rate;    // Predicted bearing rate (rad/s).
  std::vector<double> error;   // wrap(β − β̂) (rad).
  std::vector<double> signal;  // ρ'·r·∂r/∂τ (score density; 0 for left-out bearings).
  std::vector<double> weight;  // ρ'.
  std::vector<size_t> index;   // Flat index → (run, bearing) in log order.
};

double LogStart(const BearingLog& log) {
  double start = std::numeric_limits<double>::infinity();
  for (const BearingRun& run : log.runs) {
    if (!run.odometry.empty()) start = std::min(start, run.odometry.front().t_s);
  }
  return std::isfinite(start) ? start : 0.0;
}

// `problem` models τ (the sensitivity is that of τ at its current value).
BearingSeries Series(const BearingLog& log, const BearingProblem& problem, double log_start_s) {
  BearingSeries series;
  const BearingParams p = problem.params();
  const double r = log.meta.wheel_radius_m;
  const double b = log.meta.wheelbase_m;
  const double delta_b = 1.0 / (b * p.xi_per_m);
  const std::vector<std::vector<double>> errors = problem.BearingErrors();
  std::vector<std::vector<BearingProblem::BearingTermInfo>> terms(log.runs.size());
  for (const auto& info : problem.BearingTerms()) {
    if (terms[info.run].empty()) terms[info.run].resize(log.runs[info.run].bearings.size());
    terms[info.run][info.bearing] = info;
  }
  constexpr double kHalfWindow = 0.1;  // s: speeds from the encoders over t ± this.
  for (size_t i = 0; i < log.runs.size(); ++i) {
    const BearingRun& run = log.runs[i];
    for (size_t j = 0; j < run.bearings.size(); ++j) {
      const double t = run.bearings[j].t_s;
      const Pose2d motion = IntegrateEncoders(run.odometry, t - kHalfWindow, t + kHalfWindow, r, b,
                                              1.0, p.delta, delta_b);
      series.t_s.push_back(t - log_start_s);
      series.speed.push_back(motion(0) / (2.0 * kHalfWindow));
      series.turn.push_back(motion(2) / (2.0 * kHalfWindow));
      const bool has_term = !terms[i].empty() && terms[i][j].run == static_cast<int>(i) &&
                            terms[i][j].bearing == static_cast<int>(j);
      const BearingProblem::BearingTermInfo info =
          has_term ? terms[i][j] : BearingProblem::BearingTermInfo{};
      series.rate.push_back(-info.sensitivity * problem.noise().bearing_sigma_rad);
      series.error.push_back(errors[i][j]);
      series.signal.push_back(has_term ? info.rho1 * info.residual * info.sensitivity : 0.0);
      series.weight.push_back(has_term ? info.rho1 : 0.0);
    }
  }
  return series;
}

const std::vector<double>& Covariate(const BearingSeries& s, size_t which) {
  switch (which) {
    case 0:
      return s.t_s;
    case 1:
      return s.speed;
    case 2:
      return s.turn;
    default:
      return s.rate;
  }
}

const char* CovariateUnit(size_t which) {
  static const char* kUnits[] = {"s", "m/s", "rad/s", "rad/s"};
  return kUnits[which];
}

const char* CovariateWords(size_t which) {
  static const char* kWords[] = {"time", "the speed", "the angular rate",
                                 "the predicted bearing rate"};
  return kWords[which];
}

Eigen::MatrixXd Column(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

CovariateProfile Profile(size_t which, const BearingSeries& before, const BearingSeries& after,
                         int bins, bool with_signal) {
  CovariateProfile profile;
  profile.name = BearingCovariateNames()[which];
  profile.unit = CovariateUnit(which);
  profile.channel_labels = {"bearing error [mrad]"};
  profile.channel_scales = {1e3};
  if (with_signal) {
    profile.channel_labels.push_back("along the effect [σ]");
    profile.channel_scales.push_back(1.0);
  }
  const auto values = [&](const BearingSeries& s) {
    Eigen::MatrixXd v(s.error.size(), with_signal ? 2 : 1);
    v.col(0) = Column(s.error);
    if (with_signal) v.col(1) = Column(s.signal);
    return v;
  };
  const auto weights = [](const BearingSeries& s) {
    Eigen::VectorXd w = Column(s.weight);
    return w;
  };
  const BinnedMeans b =
      BinByCovariate(Covariate(before, which), values(before), weights(before), bins);
  const BinnedMeans a =
      BinByCovariate(Covariate(before, which), values(after), weights(after), bins);
  profile.center = b.center;
  profile.before_mean = b.mean;
  profile.before_stderr = b.standard_error;
  profile.after_mean = a.mean;
  profile.after_stderr = a.standard_error;
  const BinnedMeans be =
      BinByCovariate(Covariate(before, which), Column(before.error), weights(before), bins);
  const BinnedMeans ae =
      BinByCovariate(Covariate(before, which), Column(after.error), weights(after), bins);
  profile.before_statistic = be.statistic;
  profile.after_statistic = ae.statistic;
  profile.before_p_value = be.p_value;
  profile.after_p_value = ae.p_value;
  profile.dof = be.dof;
  return profile;
}

// Structure in the residuals: binned means against each covariate and a change of the mean
// over time, Holm over the five tests.
ResidualStructure Structure(const BearingSeries& s, int bins, double alpha) {
  ResidualStructure out;
  std::vector<std::pair<double, int>> tests;  // (p, which); which = 4: the change over time.
  const Eigen::VectorXd weights = Column(s.weight);
  for (size_t c = 0; c < BearingCovariateNames().size(); ++c) {
    const BinnedMeans b = BinByCovariate(Covariate(s, c), Column(s.error), weights, bins);
    tests.emplace_back(b.p_value, static_cast<int>(c));
  }
  // The change test on errors in σ units (its CUSUM assumes unit variance per sample).
  double sigma = 0.0;
  for (double e : s.error) sigma += e * e;
  sigma = std::sqrt(sigma / std::max<size_t>(1, s.error.size()));
  size_t split = 0;
  const double change_p =
      sigma > 0.0 ? ConstantMeanPValue(Column(s.error) / sigma, 0.05, &split) : 1.0;
  tests.emplace_back(change_p, 4);
  std::sort(tests.begin(), tests.end());
  const int m = static_cast<int>(tests.size());
  for (int k = 0; k < m; ++k) {
    if (tests[k].first > alpha / (m - k)) break;
    out.found = true;
    if (tests[k].second == 4) {
      out.change_time_s = s.t_s.empty() ? 0.0 : s.t_s[std::min(split, s.t_s.size() - 1)];
      out.change_p_value = tests[k].first;
    } else if (out.covariate.empty()) {
      out.covariate = BearingCovariateNames()[tests[k].second];
      out.p_value = tests[k].first;
    }
  }
  if (!out.found) {
    out.statement =
        "The bearing residuals follow none of time, speed, angular rate and bearing "
        "rate, and their mean does not change over time (smallest " +
        PValueText(tests[0].first) + ", family-wise level " + Format("%.2g", alpha) + ").";
    return out;
  }
  std::string text = "The bearing residuals still ";
  if (!out.covariate.empty()) {
    const size_t c =
        std::find(BearingCovariateNames().begin(), BearingCovariateNames().end(), out.covariate) -
        BearingCovariateNames().begin();
    text += std::string("follow ") + CovariateWords(c) + " (binned means, " +
            PValueText(out.p_value) + ")";
  }
  if (out.change_time_s >= 0.0) {
    text += std::string(out.covariate.empty() ? "" : " and ") +
            Format("change their mean at t = %.0f s", out.change_time_s) + " (" +
            PValueText(out.change_p_value) + ")";
  }
  out.statement = text + ": a mismatch that the adopted model does not explain.";
  return out;
}

// The held-out cost ½Σρ and inlier RMS of bearings left out of a fit, summed over the folds.
struct HeldOut {
  double cost = 0.0;
  double sum_sq = 0.0;
  int count = 0;
  double rms() const { return count > 0 ? std::sqrt(sum_sq / count) : 0.0; }
};

StatusOr<HeldOut> CrossValidate(const BearingLog& log, const BearingProblem& start,
                                const BearingAdjustmentOptions& adjustment, const Model& model,
                                int folds, const ceres::LossFunction* loss) {
  HeldOut out;
  const BearingParams params = start.params();
  const std::vector<std::vector<Pose2d>> poses = start.poses();
  const double sigma = start.noise().bearing_sigma_rad;
  for (int f = 0; f < folds; ++f) {
    std::vector<std::vector<bool>> use(log.runs.size());
    for (size_t i = 0; i < log.runs.size(); ++i) {
      const size_t n = log.runs[i].bearings.size();
      for (size_t j = 0; j < n; ++j) use[i].push_back(static_cast<int>(j * folds / n) != f);
    }
    Model m = model;
    m.time_offset_s = start.time_offset();
    ProblemPtr problem = MakeProblem(log, params, poses, start.noise(), adjustment, m, use);
    const Status status = problem->Solve();
    if (!status.ok()) return status;
    const std::vector<std::vector<double>> errors = problem->BearingErrors();
    for (size_t i = 0; i < errors.size(); ++i) {
      for (size_t j = 0; j < errors[i].size(); ++j) {
        if (use[i][j]) continue;
        const double z = errors[i][j] / sigma;
        double rho[3] = {z * z, 1.0, 0.0};
        if (loss != nullptr) loss->Evaluate(z * z, rho);
        out.cost += 0.5 * rho[0];
        if (z * z <= kInlierChi2) {
          out.sum_sq += errors[i][j] * errors[i][j];
          ++out.count;
        }
      }
    }
  }
  return out;
}

std::string ShiftWords(const BearingParamVector& shift, const BearingParamVector& sigmas) {
  std::vector<int> order(kNumBearingParams);
  for (int i = 0; i < kNumBearingParams; ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](int a, int b) { return std::abs(sigmas(a)) > std::abs(sigmas(b)); });
  std::string text;
  for (int rank = 0; rank < 2; ++rank) {
    const int i = order[rank];
    if (rank > 0 && std::abs(sigmas(i)) < 1.0) break;
    if (rank > 0) text += " and ";
    text += std::string(kBearingParamNames[i]) + " " + Format("%+.3g", shift(i) * ParamScale(i)) +
            ParamUnit(i) + Format(" (%.1f σ)", std::abs(sigmas(i)));
  }
  return text;
}

void WriteStatement(BearingFinding* f) {
  if (f->no_information) {
    f->statement =
        "The log's motion does not excite time_offset at all (no sensitivity): it can "
        "be neither found nor excluded.";
    return;
  }
  if (f->confounded) {
    f->statement =
        "A clock offset of the bearings is exactly absorbed by the runs' start poses "
        "(constant-speed motion only moves each run along its path): this log cannot "
        "see it, so it is not a finding.";
    return;
  }
  const std::string tested = Format("score test %.1f, ", f->statistic) + PValueText(f->p_value) +
                             Format(", %.0f %% of it absorbable by the base unknowns",
                                    100.0 * std::max(0.0, f->concealment));
  if (f->significant) {
    std::string text = Format(f->value >= 0.0 ? "The bearings are stamped %.1f ± %.1f ms early "
                                                "relative to the encoders"
                                              : "The bearings are stamped %.1f ± %.1f ms late "
                                                "relative to the encoders",
                              std::abs(f->value) * 1e3, f->stddev * 1e3);
    text += " (" + tested + ")";
    text += "; the base fit had absorbed it as " + ShiftWords(f->base_shift, f->base_shift_sigmas);
    text += Format("; modelling it cuts the held-out residual cost by %.1f %%",
                   100.0 * f->heldout_reduction);
    if (!f->location.covariate.empty()) {
      const size_t c = std::find(BearingCovariateNames().begin(), BearingCovariateNames().end(),
                                 f->location.covariate) -
                       BearingCovariateNames().begin();
      text += std::string("; it follows ") + CovariateWords(c);
      text += WindowWords(f->location);
    }
    f->statement = text + ".";
    return;
  }
  std::string text = "No time_offset adopted: " + tested;
  if (f->one_step_stddev > 0.0) {
    text +=
        Format("; one-step estimate %.1f ± %.1f ms", f->one_step * 1e3, f->one_step_stddev * 1e3);
  }
  if (f->refitted) {
    if (f->lr_p_value > f->holm_level) {
      text += "; the likelihood-ratio test did not confirm it (" + PValueText(f->lr_p_value) + ")";
    } else {
      text += Format("; the held-out blocks did not confirm it (held-out cost %+.2f %%)",
                     -100.0 * f->heldout_reduction);
    }
  }
  f->statement = text + ".";
}

MismatchLocation Locate(const BearingSeries& s, int bins, double alpha) {
  MismatchLocation location;
  double best = -1.0;
  for (size_t c = 0; c < BearingCovariateNames().size(); ++c) {
    const BinnedMeans b = BinByCovariate(Covariate(s, c), Column(s.error), Column(s.weight), bins);
    if (b.explained > best) {
      best = b.explained;
      location.covariate = BearingCovariateNames()[c];
      location.explained = b.explained;
    }
  }
  // Windows: CUSUM segments of the score density (in its own σ units).
  Eigen::VectorXd signal = Column(s.signal);
  const double scale = std::sqrt(signal.squaredNorm() / std::max<Eigen::Index>(1, signal.size()));
  if (scale > 0.0) signal /= scale;
  const double total = signal.sum();
  for (const SeriesSegment& segment :
       SegmentMeans(signal, alpha, 4, 0.05, std::max<size_t>(10, s.t_s.size() / 20))) {
    MismatchLocation::Window w;
    w.start_s = s.t_s[segment.begin];
    w.end_s = s.t_s[segment.end - 1];
    w.share = total != 0.0
                  ? signal.segment(segment.begin, segment.end - segment.begin).sum() / total
                  : 0.0;
    w.rate = segment.mean(0) * scale;
    location.windows.push_back(w);
  }
  return location;
}

}  // namespace

const std::vector<std::string>& BearingCovariateNames() {
  static const std::vector<std::string> names = {"time", "speed", "angular_rate", "bearing_rate"};
  return names;
}

StatusOr<BearingDiagnosis> DiagnoseBearing(const BearingLog& log,
                                           const BearingDiagnosisOptions& options) {
  const auto clock = std::chrono::steady_clock::now();
  const auto report = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  const std::string source = log.source.empty() ? "bearing log" : log.source;
  BearingDiagnosis out;
  StatusOr<BearingCalibrationResult> base = CalibrateBearing(log, options.calibration);
  if (!base.ok()) return base.status();
  out.base = *base;
  out.samples = base->samples;
  const BearingAdjustmentOptions& adjustment = options.calibration.adjustment;
  const std::unique_ptr<ceres::LossFunction> loss =
      MakeLossFunction(adjustment.loss, adjustment.loss_scale);
  const double log_start = LogStart(log);

  // The base problem at the base optimum (re-solved: a few iterations at most).
  ProblemPtr p0 = MakeProblem(log, base->estimate, base->poses, base->noise, adjustment, {});
  Status status = p0->Solve();
  if (!status.ok()) return Status::Error(source + ": " + status.message());
  std::vector<std::vector<bool>> inlier = Inliers(*p0);
  if (!p0->VarianceComponents(inlier).ok()) {
    return Status::Error(source + ": the base fit's leverages could not be computed");
  }
  double lr_scale = 1.0, lambda = 1.0;
  p0->LossConstants(&lr_scale, &lambda);
  const double cost0 = p0->Cost();

  out.baseline.estimate = base->estimate;
  out.baseline.stddev = base->stddev;
  out.baseline.has_metric = base->has_metric;
  out.baseline.metric = base->metric;
  out.baseline.metric_stddev = base->metric_stddev;
  std::tie(out.baseline.rms_rad, out.baseline.inliers) = InlierRms(p0->BearingErrors(), inlier);
  out.baseline.robust_cost = cost0;
  out.final_fit = out.baseline;

  // Score test of τ = 0: τ added, held at 0.
  ProblemPtr p1 =
      MakeProblem(log, p0->params(), p0->poses(), p0->noise(), adjustment, Model{true, 0.0, true});
  if (!p1->VarianceComponents(inlier).ok()) {
    return Status::Error(source + ": the base fit's leverages could not be computed");
  }
  BearingFinding f;
  f.holm_level = options.alpha;
  double score = 0.0;
  p1->Cost(&score);
  double a_tt = 0.0;
  for (const auto& info : p1->BearingTerms())
    a_tt += info.rho1 * info.sensitivity * info.sensitivity;
  const BearingSeries before = Series(log, *p1, log_start);
  out.structure_before = Structure(before, options.covariate_bins, options.alpha);
  StatusOr<BearingProblem::TimeOffsetCovariance> cov = p1->CovarianceWithTimeOffset();
  const double c_tt = cov.ok() ? cov->joint(kNumBearingParams, kNumBearingParams) : 0.0;
  if (!(a_tt > 0.0)) {
    f.no_information = true;
  } else if (!cov.ok() || !(c_tt > 0.0) || 1.0 / (c_tt * a_tt) < kConfoundedInformation) {
    f.confounded = true;
    f.confounded_with = {"start_pose"};
    f.concealment = 1.0;
  } else {
    const double kappa = lr_scale / lambda;
    f.concealment = 1.0 - 1.0 / (c_tt * a_tt);
    f.statistic = score * score * c_tt / (lr_scale * lambda);
    f.p_value = ChiSquareSurvival(f.statistic, 1);
    f.score_significant = f.p_value <= options.alpha;
    f.one_step = -c_tt * score / lambda;
    f.one_step_stddev = std::sqrt(kappa * c_tt);
    f.absorbed = cov->joint.topRightCorner<kNumBearingParams, 1>() * score / lambda;
    f.value = f.one_step;
    f.stddev = f.one_step_stddev;
  }
  report(Format("time_offset: score test %.1f, ", f.statistic) + PValueText(f.p_value) +
         Format(", one-step %.1f ± %.1f ms", f.one_step * 1e3, f.one_step_stddev * 1e3));

  ProblemPtr final_problem;
  if (f.score_significant) {
    // Refit with τ free, from the one-step estimate.
    ProblemPtr p2 = MakeProblem(log, p0->params(), p0->poses(), p0->noise(), adjustment,
                                Model{true, f.one_step, false});
    status = p2->Solve();
    if (!status.ok()) return Status::Error(source + ": " + status.message());
    f.refitted = true;
    const double cost2 = p2->Cost();
    f.lr_statistic = std::max(0.0, 2.0 * (cost0 - cost2) / lr_scale);
    f.lr_p_value = ChiSquareSurvival(f.lr_statistic, 1);
    f.delta_aic = f.lr_statistic - 2.0;
    f.delta_bic = f.lr_statistic - std::log(static_cast<double>(std::max(1, base->samples)));
    const int folds = std::max(2, options.cv_blocks);
    StatusOr<HeldOut> held_before = CrossValidate(log, *p0, adjustment, {}, folds, loss.get());
    if (!held_before.ok()) return Status::Error(source + ": " + held_before.message());
    StatusOr<HeldOut> held_after =
        CrossValidate(log, *p2, adjustment, Model{true, 0.0, false}, folds, loss.get());
    if (!held_after.ok()) return Status::Error(source + ": " + held_after.message());
    f.heldout_cost_before = held_before->cost;
    f.heldout_cost_after = held_after->cost;
    f.heldout_rms_before = held_before->rms();
    f.heldout_rms_after = held_after->rms();
    f.heldout_reduction = 1.0 - held_after->cost / held_before->cost;
    const bool confirmed = f.lr_p_value <= f.holm_level && held_after->cost < held_before->cost;
    report(Format("  LR %.1f, held-out %+.3f %%", f.lr_statistic, -100.0 * f.heldout_reduction) +
           (confirmed ? " → adopted" : ""));
    if (confirmed) {
      f.significant = true;
      final_problem = std::move(p2);
    } else {
      out.notes.push_back(f.lr_p_value > f.holm_level
                              ? "time_offset passed the score test but not the likelihood ratio."
                              : "time_offset passed the score test but did not predict the "
                                "held-out blocks better.");
    }
  }

  if (final_problem) {
    // The final fit's covariance, with K as the base fit reported it (see CalibrateBearing).
    BearingProblem& p2 = *final_problem;
    const std::vector<std::vector<bool>> final_inlier = Inliers(p2);
    if (!p2.VarianceComponents(final_inlier).ok()) {
      return Status::Error(source + ": the final fit's leverages could not be computed");
    }
    BearingFitReport& fit = out.final_fit;
    fit.with_time_offset = true;
    fit.estimate = p2.params();
    fit.robust_cost = p2.Cost();
    std::tie(fit.rms_rad, fit.inliers) = InlierRms(p2.BearingErrors(), final_inlier);
    const BearingSeries after = Series(log, p2, log_start);
    BearingNoise reported = p2.noise();
    reported.encoder_k = std::max(reported.encoder_k, base->covariance_encoder_k);
    p2.SetNoise(reported);
    if (log.meta.initial_distance) {
      const InitialDistance& d = *log.meta.initial_distance;
      const size_t run = std::find_if(log.runs.begin(), log.runs.end(),
                                      [&](const BearingRun& r) { return r.id == d.run; }) -
                         log.runs.begin();
      StatusOr<BearingScaledWithDistanceMatrix> joint = p2.CovarianceWithStartDistance(run);
      if (!joint.ok()) return Status::Error(source + ": " + joint.message());
      fit.stddev = joint->diagonal().head<kNumBearingParams>().cwiseMax(0.0).cwiseSqrt();
      Eigen::Matrix<double, kNumBearingMetricParams, kNumBearingParams + 1> jacobian;
      fit.metric = BearingMetricFromScaled(fit.estimate, p2.StartDistance(run), d.meters,
                                           log.meta.wheelbase_m, &jacobian);
      fit.metric_stddev =
          (jacobian * *joint * jacobian.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
      fit.has_metric = true;
    } else {
      StatusOr<BearingParamMatrix> c = p2.Covariance();
      if (!c.ok()) return Status::Error(source + ": " + c.message());
      fit.stddev = c->diagonal().cwiseMax(0.0).cwiseSqrt();
    }
    StatusOr<BearingProblem::TimeOffsetCovariance> with_offset = p2.CovarianceWithTimeOffset();
    if (!with_offset.ok()) return Status::Error(source + ": " + with_offset.message());
    fit.time_offset_s = p2.time_offset();
    fit.time_offset_stddev_s =
        std::sqrt(std::max(0.0, with_offset->joint(kNumBearingParams, kNumBearingParams)) *
                  p2.covariance_scale());
    f.value = fit.time_offset_s;
    f.stddev = fit.time_offset_stddev_s;
    f.base_shift = ToVector(out.baseline.estimate) - ToVector(fit.estimate);
    for (int i = 0; i < 2; ++i) f.base_shift(i) = WrapAngle(f.base_shift(i));
    f.base_shift_sigmas = f.base_shift.cwiseQuotient(out.baseline.stddev);
    f.location = Locate(before, options.covariate_bins, options.alpha);
    const size_t which = std::find(BearingCovariateNames().begin(), BearingCovariateNames().end(),
                                   f.location.covariate) -
                         BearingCovariateNames().begin();
    f.profile = Profile(which, before, after, options.covariate_bins, true);
    for (size_t c = 0; c < BearingCovariateNames().size(); ++c) {
      out.covariates.push_back(Profile(c, before, after, options.covariate_bins, false));
    }
    out.structure_after = Structure(after, options.covariate_bins, options.alpha);
    out.adopted.push_back(f.name);
  } else {
    for (size_t c = 0; c < BearingCovariateNames().size(); ++c) {
      out.covariates.push_back(Profile(c, before, before, options.covariate_bins, false));
    }
    out.structure_after = out.structure_before;
    if (f.score_significant || out.structure_before.found) {
      f.location = Locate(before, options.covariate_bins, options.alpha);
    }
  }
  WriteStatement(&f);
  out.findings.push_back(f);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock).count();
  return out;
}

}  // namespace calib
