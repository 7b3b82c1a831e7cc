#include <calib/solvers/diagnosis/confirmation.h>
#include <calib/solvers/diagnosis/multiple_testing.h>
#include <calib/solvers/diagnosis/statement.h>
#include <calib/solvers/laser/laser_dead_reckoning.h>
#include <calib/solvers/laser/laser_diagnosis.h>
#include <calib/solvers/laser/laser_diagnosis_internal.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace calib {
namespace laser_diagnosis {

bool UsesBoundarySpeeds(LaserEffect effect) {
  return effect == LaserEffect::kTimeOffset || effect == LaserEffect::kLongitudinalSlip;
}

std::vector<int> EffectColumns(LaserEffect effect) {
  const LaserEffectInfo& info = EffectInfo(effect);
  std::vector<int> columns;
  for (int i = 0; i < info.size; ++i) columns.push_back(kNumLaserParams + info.offset + i);
  return columns;
}

double LaserLikelihoodRatioScale(const LaserEffectEvaluation& evaluation) {
  return LikelihoodRatioScale(evaluation.residual.rowwise().squaredNorm(), evaluation.rho1,
                              evaluation.rho2, 3);
}

RobustFitBlocks Blocks(const LaserEffectEvaluation& evaluation, const std::vector<int>& columns) {
  RobustFitBlocks blocks;
  blocks.residual = evaluation.residual;
  blocks.jacobian = SelectColumns(evaluation.jacobian, columns);
  blocks.rho1 = evaluation.rho1;
  blocks.rho2 = evaluation.rho2;
  return blocks;
}

namespace {

// The whitening of the effect fits: the base fit's robust noise level (or the given one).
Eigen::Matrix3d SqrtInformation(const std::vector<LaserInterval>& intervals,
                                const LaserCalibrationResult& base,
                                const LaserDiagnosisOptions& options) {
  if (options.calibration.noise_sigma) {
    return options.calibration.noise_sigma->cwiseInverse().asDiagonal();
  }
  // The base fit's own last noise estimate is this one (at its estimate): not computed again.
  const Eigen::Vector3d sigma =
      base.robust_noise_sigma.size() == 1
          ? base.robust_noise_sigma.front()
          : RobustNoiseSigma(LaserIntervalErrors(intervals, base.estimate));
  return sigma.cwiseInverse().asDiagonal();
}

// Contiguous held-out blocks of the intervals.
void MakeFolds(Context* context) {
  const size_t n = context->intervals.size();
  const int blocks = std::clamp(context->options.cv_blocks, 2, 20);
  for (int f = 0; f < blocks; ++f) {
    std::vector<bool> test(n, false);
    for (size_t k = n * f / blocks; k < n * (f + 1) / blocks; ++k) test[k] = true;
    std::vector<bool> train(n);
    for (size_t k = 0; k < n; ++k) train[k] = !test[k];
    context->test_masks.push_back(test);
    context->train_masks.push_back(train);
  }
}

std::vector<CandidateState> MakeCandidates(const LaserDiagnosisOptions& options) {
  std::vector<CandidateState> candidates;
  for (LaserEffect effect : options.candidates) {
    if (std::any_of(candidates.begin(), candidates.end(),
                    [&](const CandidateState& c) { return c.effect == effect; })) {
      continue;
    }
    CandidateState state;
    state.effect = effect;
    LaserFinding& f = state.finding;
    f.effect = effect;
    f.name = LaserEffectName(effect);
    f.unit = effect == LaserEffect::kWheelRadiusChange ? "s" : EffectInfo(effect).unit;
    f.absorbed = f.base_shift = f.base_shift_sigmas = LaserParamVector::Zero();
    f.absorbed_share = 0.0;
    candidates.push_back(state);
  }
  return candidates;
}

// A radius change that is not modelled yet is evaluated with every interval after it (its
// Jacobian columns then hold the sensitivity R_k of a change before interval k). At γ = 0 this
// changes nothing else: the residuals and the other columns are the model's own.
LaserEffectModel StepEvaluationModel(const LaserEffectModel& model) {
  LaserEffectModel evaluation_model = model;
  if (!model.Has(LaserEffect::kWheelRadiusChange)) evaluation_model.change_time_s = -kInfinity;
  return evaluation_model;
}

// Whether the search still stands at the base fit in the base fit's whitening.
bool AtBase(const LaserEffectData& data, const LaserEffectFit& current,
            const LaserCalibration& base_calibration) {
  return !data.has_interval_sqrt_information() && current.model.effects.empty() &&
         current.calibration.ToVector() == base_calibration.ToVector();
}

// The score test of one candidate at the current fit; false when it cannot be tested
// (confounded or not excited), which ends its search.
bool ScoreCandidate(const Context& context, const ScoreTester& tester,
                    const LaserEffectEvaluation& evaluation, const LaserEffectModel& model,
                    int step, CandidateState* c) {
  const Eigen::MatrixXd sensitivity = SelectColumns(evaluation.jacobian, EffectColumns(c->effect));
  LaserFinding& f = c->finding;
  f.step = step;
  if (c->effect == LaserEffect::kWheelRadiusChange) {
    const ScoreTester::ChangeScan scan =
        tester.ScanChange(sensitivity, context.options.change_trim);
    c->test = scan.at_best;
    c->test.p_value = scan.p_value;
    c->change_time_s = context.intervals[scan.location].start_s;
  } else {
    c->test = tester.Test(sensitivity);
  }
  f.statistic = c->test.statistic;
  f.dof = c->test.dof;
  f.p_value = c->test.p_value;
  f.concealment = c->test.concealment;
  f.one_step = c->test.gamma;
  f.one_step_stddev = c->test.gamma_covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  f.absorbed = c->test.absorbed.head<kNumLaserParams>();
  if (c->test.identifiable) return true;
  if (std::isnan(c->test.concealment)) {
    f.no_information = true;
  } else {
    f.confounded = true;
    f.confounded_with = ConfoundedWith(c->test, tester.blocks(), sensitivity, FreeNames(model));
  }
  c->done = true;
  return false;
}

// One forward step: score tests of the remaining candidates at the current fit, Holm over the
// testable ones, then the refit and confirmation of those that pass, strongest first, until one
// is adopted. Returns whether one was.
StatusOr<bool> ForwardStep(const Context& context, int step, bool may_adopt,
                           const LaserEffectEvaluation* at_current,
                           std::vector<CandidateState>* candidates, Search* search) {
  const LaserEffectModel& model = search->current.model;
  LaserEffectEvaluation own;
  if (at_current == nullptr) {
    own =
        EvaluateLaserEffects(context.data, StepEvaluationModel(model), search->current.calibration);
  }
  const LaserEffectEvaluation& evaluation = at_current != nullptr ? *at_current : own;
  const ScoreTester tester(Blocks(evaluation, model.FreeColumns()), context.options.hac_lag);
  if (!tester.ok()) return Status::NotObservable("the fit's information matrix is singular");
  std::vector<CandidateState*> testable;
  for (CandidateState& c : *candidates) {
    if (!c.done && ScoreCandidate(context, tester, evaluation, model, step, &c)) {
      testable.push_back(&c);
    }
  }
  if (testable.empty()) return false;
  std::vector<double> p_values;
  for (const CandidateState* c : testable) p_values.push_back(c->test.p_value);
  std::vector<CandidateState*> passing;
  for (const HolmStep& holm : Holm(p_values, context.options.alpha)) {
    LaserFinding& f = testable[holm.index]->finding;
    f.holm_level = holm.level;
    f.score_significant = holm.rejected;
    if (holm.rejected) passing.push_back(testable[holm.index]);
  }
  if (context.options.progress) {
    context.options.progress("step " + std::to_string(step) + ": " +
                             std::to_string(passing.size()) + " candidate(s) pass the score test");
  }
  if (!may_adopt) return false;
  for (CandidateState* c : passing) {
    CALIB_ASSIGN_OR_RETURN(const bool adopted, RefitAndConfirm(context, evaluation, c, search));
    if (adopted) return true;
  }
  return false;
}

std::vector<std::string> Notes(const std::vector<LaserInterval>& intervals,
                               const LaserEffectModel& model) {
  std::vector<std::string> notes;
  if (std::any_of(model.effects.begin(), model.effects.end(), UsesBoundarySpeeds)) {
    notes.push_back(
        model.boundary == BoundarySpeedModel::kPiecewiseConstant
            ? "boundary speeds: constant within intervals, one-sided at the jumps (it fitted "
              "better than smooth speeds and passed the test of its |δ| term)"
            : "boundary speeds: smooth (instantaneous speeds from the cumulative wheel angles)");
  }
  if (std::any_of(intervals.begin(), intervals.end(),
                  [](const LaserInterval& in) { return in.gap_before; })) {
    notes.push_back(
        "the log has gaps: the time offset and the longitudinal slip assume "
        "the speed continues across them");
  }
  return notes;
}

// The radii after a change, r·(1 + γ), and their σ by the delta method (ignoring the radius–γ
// correlation's sign: a bound).
void RadiiAfter(const LaserCalibration& cal, const Eigen::Vector2d& gamma,
                const Eigen::Vector2d& radius_sigma, const Eigen::Vector2d& gamma_sigma,
                LaserFinding* f) {
  const double rl = cal.odometry.left_radius_m, rr = cal.odometry.right_radius_m;
  f->r_l_after = rl * (1.0 + gamma(0));
  f->r_r_after = rr * (1.0 + gamma(1));
  f->r_l_after_stddev = std::hypot(radius_sigma(0) * (1.0 + gamma(0)), rl * gamma_sigma(0));
  f->r_r_after_stddev = std::hypot(radius_sigma(1) * (1.0 + gamma(1)), rr * gamma_sigma(1));
}

// Values from the final fit for adopted effects, else the one-step estimates.
void SetValues(const Context& context, const Search& search, const LaserDiagnosis& diagnosis,
               CandidateState* c) {
  LaserFinding& f = c->finding;
  const LaserEffectInfo& info = EffectInfo(c->effect);
  const LaserEffectModel& model = search.current.model;
  const LaserFitReport& fit = diagnosis.final_fit;
  const bool change = c->effect == LaserEffect::kWheelRadiusChange;
  if (f.significant) {
    f.value = change ? fit.change_time_s : model.gamma(info.offset);
    f.stddev = change ? fit.change_time_stddev_s : fit.gamma_stddev(info.offset);
    for (const Adoption& a : search.adoptions) {
      if (a.effect != c->effect) continue;
      f.base_shift = a.shift;
      f.absorbed_share = a.absorbed_share;
      f.base_shift_sigmas = ShiftInSigmas(a.shift, diagnosis.baseline.stddev);
    }
    if (change) {
      RadiiAfter(search.current.calibration, model.gamma.segment<2>(info.offset),
                 fit.stddev.head<2>(), fit.gamma_stddev.segment<2>(info.offset), &f);
    }
  } else if (f.implausible && !change) {
    f.stddev = f.one_step_stddev.size() > 0 ? f.one_step_stddev(0) : 0.0;  // f.value: the refit.
  } else if (f.testable()) {
    const auto entry = [](const Eigen::VectorXd& v, Eigen::Index i) {
      return v.size() > i ? v(i) : 0.0;
    };
    f.value = change ? c->change_time_s - context.log_start_s : entry(f.one_step, 0);
    f.stddev = change ? 0.0 : entry(f.one_step_stddev, 0);
    if (change) {
      // One-step radii: no σ of the base radii in the bound.
      const Eigen::Vector2d gamma(entry(f.one_step, 0), entry(f.one_step, 1));
      const Eigen::Vector2d sigma(entry(f.one_step_stddev, 0), entry(f.one_step_stddev, 1));
      RadiiAfter(search.current.calibration, gamma, Eigen::Vector2d::Zero(), sigma, &f);
    }
  }
}

// Adopted findings first, in the order adopted; then by p-value (untestable ones last).
std::vector<LaserFinding> Ordered(const std::vector<CandidateState>& candidates,
                                  const std::vector<LaserEffect>& adopted) {
  std::vector<LaserFinding> findings;
  for (LaserEffect effect : adopted) {
    for (const CandidateState& c : candidates) {
      if (c.effect == effect) findings.push_back(c.finding);
    }
  }
  std::vector<const CandidateState*> rest;
  for (const CandidateState& c : candidates) {
    if (!c.finding.significant) rest.push_back(&c);
  }
  std::stable_sort(rest.begin(), rest.end(), [](const CandidateState* a, const CandidateState* b) {
    const auto key = [](const CandidateState* c) {
      return c->finding.testable() ? c->finding.p_value : 2.0;
    };
    return key(a) < key(b);
  });
  for (const CandidateState* c : rest) findings.push_back(c->finding);
  return findings;
}

}  // namespace
}  // namespace laser_diagnosis

StatusOr<LaserDiagnosis> DiagnoseLaser(const std::vector<LaserInterval>& intervals,
                                       const LaserDiagnosisOptions& options) {
  using namespace laser_diagnosis;  // NOLINT: the adapter's internals.
  const auto start_time = std::chrono::steady_clock::now();
  CALIB_RETURN_IF_ERROR(ValidateLaserIntervals(intervals));
  if (intervals.size() < 50) {
    return Status::InvalidInput("diagnosis needs at least 50 intervals (the log has " +
                                std::to_string(intervals.size()) + ")");
  }
  // The effects' contexts and the folds need the intervals only: made first, so that a screen
  // beside a calibration makes them while it waits for that calibration's closed forms.
  LaserEffectData data(intervals, Eigen::Matrix3d::Identity(), options.calibration.refinement);
  Context context{intervals, options, data, intervals.front().start_s, {}, {}};
  MakeFolds(&context);
  // 1. The robust base fit, whitened by its robust noise level (the stamp jitter is a candidate
  // of the diagnosis, not part of its base fit).
  LaserCalibrationOptions base_options = options.calibration;
  base_options.interval_jitter = false;
  // Only a seed of the effect fits below, which use the problem's own loss.
  base_options.refinement.redescending_scale = 0.0;
  base_options.estimate_only = true;  // Its estimate seeds the effect fits; nothing else is read.
  CALIB_ASSIGN_OR_RETURN(const LaserCalibrationResult base,
                         CalibrateLaser(intervals, base_options));
  data.SetSqrtInformation(SqrtInformation(intervals, base, options));
  LaserEffectModel model;
  model.boundary = options.boundary == BoundaryChoice::kPiecewiseConstant
                       ? BoundarySpeedModel::kPiecewiseConstant
                       : BoundarySpeedModel::kSmooth;
  Search search;
  CALIB_ASSIGN_OR_RETURN(search.current, FitLaserEffects(data, model, base.estimate));
  // One evaluation of the base fit serves its report, the first step's score tests and, when
  // nothing is adopted, the final report (reports read the residuals and the fit's columns only).
  const LaserEffectEvaluation base_evaluation = EvaluateLaserEffects(
      data, StepEvaluationModel(search.current.model), search.current.calibration);
  LaserDiagnosis diagnosis;
  diagnosis.samples = static_cast<int>(intervals.size());
  if (options.screen_only) {
    diagnosis.baseline.estimate = search.current.calibration;
  } else {
    diagnosis.baseline = MakeReport(context, search.current, base_evaluation, 0.0);
  }
  const LaserEffectModel diagnosis_base_model = search.current.model;
  const LaserCalibration diagnosis_base_calibration = search.current.calibration;
  if (options.progress) {
    char line[64];
    std::snprintf(line, sizeof(line), "base fit: cost %.1f", search.current.cost);
    options.progress(line);
  }

  // 2.–3. The timing step first: a confirmed stamp jitter is modelled (per-interval
  // whitening) before any physical candidate is tested. Then the forward steps; with max_effects
  // reached the candidates are still tested (step 1 always), not refitted.
  if (options.timing_candidates) CALIB_RETURN_IF_ERROR(TimingStep(context, &search, &diagnosis));
  // The baseline's residuals in the (possibly) jitter-whitened metric of the later fits.
  LaserEffectEvaluation rewhitened;
  if (data.has_interval_sqrt_information()) {
    rewhitened = EvaluateLaserEffects(data, diagnosis_base_model, diagnosis_base_calibration);
  }
  const LaserEffectEvaluation& base_evaluation_now =
      data.has_interval_sqrt_information() ? rewhitened : base_evaluation;
  std::vector<CandidateState> candidates = MakeCandidates(options);
  for (int step = 1; step <= kNumLaserEffects + 1; ++step) {
    const bool may_adopt = static_cast<int>(search.adoptions.size()) < options.max_effects;
    if (!may_adopt && step > 1) break;
    diagnosis.steps = step;
    const bool at_base = AtBase(data, search.current, diagnosis_base_calibration);
    CALIB_ASSIGN_OR_RETURN(const bool adopted,
                           ForwardStep(context, step, may_adopt,
                                       at_base ? &base_evaluation : nullptr, &candidates, &search));
    if (!adopted) break;
    diagnosis.adopted.push_back(search.adoptions.back().effect);
  }
  for (const std::string& note : Notes(intervals, search.current.model)) {
    diagnosis.notes.push_back(note);
  }
  if (options.screen_only) {
    diagnosis.structure_before =
        StructureAt(context, diagnosis_base_calibration, base_evaluation_now);
    diagnosis.findings = Ordered(candidates, diagnosis.adopted);
    return diagnosis;
  }

  // 4. The final fit, location and residual structure, then each finding's value and sentence.
  LaserEffectEvaluation refitted;
  const bool final_at_base = AtBase(data, search.current, diagnosis_base_calibration);
  if (!final_at_base) {
    refitted = EvaluateLaserEffects(data, search.current.model, search.current.calibration);
  }
  const LaserEffectEvaluation& final_evaluation = final_at_base ? base_evaluation : refitted;
  diagnosis.final_fit =
      MakeReport(context, search.current, final_evaluation, search.change_stddev_s);
  diagnosis.final_fit.stamp_jitter_s = search.jitter_s;
  diagnosis.final_fit.stamp_jitter_stddev_s = search.jitter_stddev_s;
  DescribeResiduals(context, base_evaluation_now, final_evaluation, search, &candidates,
                    &diagnosis);
  // The speed-dependent radius's reference speed (for its statement).
  const double typical_speed = data.Contexts(search.current.model).front().reference_speed;
  for (CandidateState& c : candidates) {
    SetValues(context, search, diagnosis, &c);
    c.finding.statement = LaserStatement(c.finding, typical_speed);
  }
  diagnosis.findings = Ordered(candidates, diagnosis.adopted);
  diagnosis.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return diagnosis;
}

}  // namespace calib
