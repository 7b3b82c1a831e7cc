#include <calib/solvers/bearing/bearing_diagnosis.h>
#include <calib/solvers/bearing/bearing_diagnosis_internal.h>
#include <calib/solvers/common/robust_loss.h>
#include <calib/solvers/diagnosis/confirmation.h>
#include <calib/solvers/diagnosis/statement.h>
#include <calib/solvers/stats/score_test.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <tuple>
#include <utility>

namespace calib {
namespace bearing_diagnosis {
namespace {

// Relative efficient information below which τ counts as absorbed by the base unknowns.
constexpr double kConfoundedInformation = 1e-6;

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

// What the steps share.
struct Steps {
  Steps(const BearingLog& log_in, const BearingDiagnosisOptions& options_in, std::string source_in,
        double log_start_in)
      : log(log_in), options(options_in), source(std::move(source_in)), log_start_s(log_start_in) {}
  const BearingLog& log;
  const BearingDiagnosisOptions& options;
  std::string source;  // For messages.
  double log_start_s = 0.0;
  BearingCalibrationResult base;
  ProblemPtr base_problem;  // At the base optimum.
  std::vector<std::vector<bool>> inlier;
  BearingProblem::LossConstants loss;  // Of the base fit.
  void Progress(const std::string& line) const {
    if (options.progress) options.progress(line);
  }
  // `status` with the log named in front (ok stays ok).
  Status Failed(const Status& status) const { return status.Prefixed(source + ": "); }
  Status NoLeverages(const char* fit) const {
    return Status::NotObservable(source + ": the " + fit +
                                 " fit's leverages could not be computed");
  }
};

// The base problem at the base optimum (re-solved: a few iterations at most).
Status FitBase(Steps* steps, BearingDiagnosis* out) {
  const BearingAdjustmentOptions& adjustment = steps->options.calibration.adjustment;
  const BearingCalibrationResult& base = steps->base;
  steps->base_problem =
      MakeProblem(steps->log, base.estimate, base.poses, base.noise, adjustment, {});
  BearingProblem& p0 = *steps->base_problem;
  CALIB_RETURN_IF_ERROR(steps->Failed(p0.Solve()));
  steps->inlier = Inliers(p0);
  if (!p0.VarianceComponents(steps->inlier).ok()) {
    return steps->NoLeverages("base");
  }
  steps->loss = p0.BearingLossConstants();
  out->base = base;
  out->samples = base.samples;
  BearingFitReport& fit = out->baseline;
  fit.estimate = base.estimate;
  fit.stddev = base.stddev;
  fit.has_metric = base.has_metric;
  fit.metric = base.metric;
  fit.metric_stddev = base.metric_stddev;
  std::tie(fit.rms_rad, fit.inliers) = InlierRms(p0.BearingErrors(), steps->inlier);
  fit.robust_cost = p0.Cost();
  out->final_fit = fit;
  return Status::Ok();
}

// Score test of τ = 0 on the base fit (τ added, held at 0): the score U = Σρ'·r·∂r/∂τ, C_ττ
// from the covariance with τ (calibration and poses projected out); see the header.
StatusOr<BearingSeries> ScoreTest(const Steps& steps, BearingFinding* f,
                                  ResidualStructure* structure) {
  const BearingProblem& p0 = *steps.base_problem;
  ProblemPtr p1 = MakeProblem(steps.log, p0.params(), p0.poses(), p0.noise(),
                              steps.options.calibration.adjustment, Model{true, 0.0, true});
  if (!p1->VarianceComponents(steps.inlier).ok()) {
    return steps.NoLeverages("base");
  }
  f->step = 1;
  f->holm_level = steps.options.alpha;
  double score = 0.0;
  p1->Cost(&score);
  double a_tt = 0.0;
  for (const auto& info : p1->BearingTerms()) {
    a_tt += info.rho1 * info.sensitivity * info.sensitivity;
  }
  const BearingSeries before = Series(steps.log, *p1, steps.log_start_s);
  *structure = Structure(before, steps.options);
  const StatusOr<BearingProblem::TimeOffsetCovariance> cov = p1->CovarianceWithTimeOffset();
  const double c_tt = cov.ok() ? cov->joint(kNumBearingParams, kNumBearingParams) : 0.0;
  if (!(a_tt > 0.0)) {
    f->no_information = true;
  } else if (!cov.ok() || !(c_tt > 0.0) || 1.0 / (c_tt * a_tt) < kConfoundedInformation) {
    f->confounded = true;
    f->confounded_with = {"start_pose"};
    f->concealment = 1.0;
  } else {
    const double kappa = steps.loss.likelihood_ratio_scale / steps.loss.lambda;
    f->concealment = 1.0 - 1.0 / (c_tt * a_tt);
    f->statistic = score * score * c_tt / (steps.loss.likelihood_ratio_scale * steps.loss.lambda);
    f->p_value = ChiSquareSurvival(f->statistic, 1);
    f->score_significant = f->p_value <= steps.options.alpha;
    f->one_step(0) = -c_tt * score / steps.loss.lambda;
    f->one_step_stddev(0) = std::sqrt(kappa * c_tt);
    f->absorbed = cov->joint.topRightCorner<kNumBearingParams, 1>() * score / steps.loss.lambda;
    f->value = f->one_step(0);
    f->stddev = f->one_step_stddev(0);
  }
  char line[160];
  std::snprintf(line, sizeof(line), "time_offset: score test %.1f, %s, one-step %.1f ± %.1f ms",
                f->statistic, PValueText(f->p_value).c_str(), f->one_step(0) * 1e3,
                f->one_step_stddev(0) * 1e3);
  steps.Progress(line);
  return before;
}

// The refit with τ free, from the one-step estimate (noise levels held at the base fit's), the
// likelihood ratio and the held-out blocks. Returns the refit problem when they confirm τ.
StatusOr<ProblemPtr> RefitAndConfirm(const Steps& steps, BearingFinding* f,
                                     std::vector<std::string>* notes) {
  const BearingProblem& p0 = *steps.base_problem;
  const BearingAdjustmentOptions& adjustment = steps.options.calibration.adjustment;
  ProblemPtr p2 = MakeProblem(steps.log, p0.params(), p0.poses(), p0.noise(), adjustment,
                              Model{true, f->one_step(0), false});
  CALIB_RETURN_IF_ERROR(steps.Failed(p2->Solve()));
  const double log_n = std::log(static_cast<double>(std::max(1, steps.base.samples)));
  const LikelihoodRatio lr =
      TestLikelihoodRatio(p0.Cost(), p2->Cost(), steps.loss.likelihood_ratio_scale, 1, log_n,
                          [](double statistic) { return ChiSquareSurvival(statistic, 1); });
  const std::unique_ptr<ceres::LossFunction> loss =
      MakeLossFunction(adjustment.loss, adjustment.loss_scale);
  const int folds = std::max(2, steps.options.cv_blocks);
  const StatusOr<HeldOutScore> before =
      CrossValidate(steps.log, p0, adjustment, {}, folds, loss.get());
  if (!before.ok()) return steps.Failed(before.status());
  const StatusOr<HeldOutScore> after =
      CrossValidate(steps.log, *p2, adjustment, Model{true, 0.0, false}, folds, loss.get());
  if (!after.ok()) return steps.Failed(after.status());
  const bool confirmed = Confirm(lr, *before, *after, f);
  steps.Progress(ConfirmationProgress(*f, confirmed));
  if (!confirmed) {
    notes->push_back(RejectionNote(*f));
    return ProblemPtr();
  }
  f->significant = true;
  return p2;
}

// The final fit with τ and its covariance, with K as the base fit reported it (see
// CalibrateBearing).
Status DescribeFinal(const Steps& steps, BearingProblem* p2, BearingFitReport* fit,
                     BearingSeries* after) {
  const std::vector<std::vector<bool>> final_inlier = Inliers(*p2);
  if (!p2->VarianceComponents(final_inlier).ok()) {
    return steps.NoLeverages("final");
  }
  fit->with_time_offset = true;
  fit->estimate = p2->params();
  fit->robust_cost = p2->Cost();
  std::tie(fit->rms_rad, fit->inliers) = InlierRms(p2->BearingErrors(), final_inlier);
  *after = Series(steps.log, *p2, steps.log_start_s);  // At the fitted noise levels.
  BearingNoise reported = p2->noise();
  reported.encoder_k = std::max(reported.encoder_k, steps.base.covariance_encoder_k);
  p2->SetNoise(reported);
  const StatusOr<BearingEstimateCovariance> cov = EstimateCovariance(*p2, steps.log, fit->estimate);
  if (!cov.ok()) return steps.Failed(cov.status());
  fit->stddev = cov->covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  if (cov->has_metric) {
    fit->metric = cov->metric;
    fit->metric_stddev = cov->metric_covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
    fit->has_metric = true;
  }
  const StatusOr<BearingProblem::TimeOffsetCovariance> with_offset = p2->CovarianceWithTimeOffset();
  if (!with_offset.ok()) return steps.Failed(with_offset.status());
  fit->time_offset_s = p2->time_offset();
  fit->time_offset_stddev_s = std::sqrt(
      std::max(0.0, with_offset->joint(kNumBearingParams, kNumBearingParams)) * cov->kappa);
  return Status::Ok();
}

// The adopted finding's value, shift and location; the covariate profiles before and after.
void DescribeAdopted(const Steps& steps, const BearingSeries& before, const BearingSeries& after,
                     BearingFinding* f, BearingDiagnosis* out) {
  const BearingDiagnosisOptions& options = steps.options;
  f->value = out->final_fit.time_offset_s;
  f->stddev = out->final_fit.time_offset_stddev_s;
  BearingParamVector shift = ToVector(out->baseline.estimate) - ToVector(out->final_fit.estimate);
  for (int i = 0; i < kNumBearingParams; ++i) {
    if (BearingParamTable()[i].is_angle) shift(i) = WrapAngle(shift(i));
  }
  f->base_shift = shift;
  f->base_shift_sigmas = ShiftInSigmas(f->base_shift, out->baseline.stddev);
  f->location = Locate(before, options);
  const size_t which = std::find(BearingCovariateNames().begin(), BearingCovariateNames().end(),
                                 f->location.covariate) -
                       BearingCovariateNames().begin();
  f->profile = Profile(which, before, after, options.covariate_bins, true);
  for (size_t c = 0; c < BearingCovariateNames().size(); ++c) {
    out->covariates.push_back(Profile(c, before, after, options.covariate_bins, false));
  }
  out->structure_after = Structure(after, options);
  out->adopted.push_back(f->name);
}

}  // namespace
}  // namespace bearing_diagnosis

const std::vector<std::string>& BearingCovariateNames() {
  static const std::vector<std::string> names = {"time", "speed", "angular_rate", "bearing_rate"};
  return names;
}

StatusOr<BearingDiagnosis> DiagnoseBearing(const BearingLog& log,
                                           const BearingDiagnosisOptions& given) {
  using namespace bearing_diagnosis;  // NOLINT: the adapter's internals.
  const auto clock = std::chrono::steady_clock::now();
  // Every fit here keeps the first loss, as the laser's diagnosis does: its tests compare costs
  // and scores under one loss, and an effect a redescending loss would reject still shows.
  BearingDiagnosisOptions options = given;
  options.calibration.adjustment.redescending_scale = 0.0;
  Steps steps(log, options, log.source.empty() ? "bearing log" : log.source, LogStart(log));
  // The base model takes the stamps as sample times: τ is the candidate tested here (and the
  // series, held-out blocks and inlier cuts below weigh every bearing by one σβ).
  BearingCalibrationOptions base_options = options.calibration;
  base_options.timing.time_offset = false;
  base_options.timing.stamp_jitter = false;
  base_options.timing.sensor_clock = false;
  CALIB_ASSIGN_OR_RETURN(steps.base, CalibrateBearing(log, base_options));
  BearingDiagnosis out;
  CALIB_RETURN_IF_ERROR(FitBase(&steps, &out));
  BearingFinding f;
  CALIB_ASSIGN_OR_RETURN(const BearingSeries before, ScoreTest(steps, &f, &out.structure_before));
  ProblemPtr final_problem;
  if (f.score_significant) {
    CALIB_ASSIGN_OR_RETURN(final_problem, RefitAndConfirm(steps, &f, &out.notes));
  }
  if (final_problem) {
    BearingSeries after;
    CALIB_RETURN_IF_ERROR(DescribeFinal(steps, final_problem.get(), &out.final_fit, &after));
    DescribeAdopted(steps, before, after, &f, &out);
  } else {
    for (size_t c = 0; c < BearingCovariateNames().size(); ++c) {
      out.covariates.push_back(Profile(c, before, before, options.covariate_bins, false));
    }
    out.structure_after = out.structure_before;
    if (f.score_significant || out.structure_before.found) f.location = Locate(before, options);
  }
  f.statement = BearingStatement(f);
  out.findings.push_back(f);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock).count();
  return out;
}

const ParamTable& BearingParamTable() {
  // The five scaled parameters, then the metric ones that are not among them (rho, delta_*).
  static const ParamTable table = [] {
    ParamTable t(std::begin(kBearingParams), std::end(kBearingParams));
    t.insert(t.end(), std::begin(kBearingMetricParams) + kBearingMetricRho,
             std::end(kBearingMetricParams));
    return t;
  }();
  return table;
}

}  // namespace calib

namespace calib {
namespace {

// The estimate's entries over BearingParamTable(): the observable set, then the metric set's
// rho, delta_r, delta_l, delta_b when the log gives a distance.
Eigen::VectorXd BearingEntries(const BearingParamVector& v, const BearingMetricVector& metric,
                               bool has_metric) {
  Eigen::VectorXd out(kNumBearingParams + (has_metric ? kNumBearingMetricParams - 2 : 0));
  out.head<kNumBearingParams>() = v;
  if (has_metric)
    out.tail<kNumBearingMetricParams - 2>() = metric.tail<kNumBearingMetricParams - 2>();
  return out;
}

FitReport ToFitReport(const BearingFitReport& fit) {
  FitReport out;
  if (fit.with_time_offset) out.effects.push_back("time_offset");
  const ParamTable& table = BearingParamTable();
  out.params.assign(table.begin(), table.begin() + kNumBearingParams +
                                       (fit.has_metric ? kNumBearingMetricParams - 2 : 0));
  out.estimate = BearingEntries(ToVector(fit.estimate), ToVector(fit.metric), fit.has_metric);
  out.stddev = BearingEntries(fit.stddev, fit.metric_stddev, fit.has_metric);
  out.rms = Eigen::VectorXd::Constant(1, fit.rms_rad);
  out.rms_units = {"rad"};
  out.robust_cost = fit.robust_cost;
  out.inliers = fit.inliers;
  if (fit.with_time_offset) {
    EffectValue value;
    value.name = "time_offset";
    value.value = fit.time_offset_s;
    value.stddev = fit.time_offset_stddev_s;
    value.unit = "s";
    out.effect_values.push_back(value);
  }
  return out;
}

}  // namespace

DiagnosisReport ToDiagnosisReport(const BearingDiagnosis& diagnosis) {
  DiagnosisReport out;
  out.problem = "bearing";
  out.units = "m, rad, s; eta and xi in 1/m";
  out.steps = 1;
  CopyCommonFields(diagnosis, &out);
  out.params.assign(BearingParamTable().begin(), BearingParamTable().begin() + kNumBearingParams);
  out.baseline = ToFitReport(diagnosis.baseline);
  out.final_fit = ToFitReport(diagnosis.final_fit);
  for (const BearingFinding& f : diagnosis.findings) out.findings.push_back({f, {}});
  out.adopted = diagnosis.adopted;
  return out;
}

}  // namespace calib
