#include <calib/core/text_format.h>
#include <calib/core/text_number.h>
#include <calib/solvers/common/outlier_share.h>
#include <calib/solvers/common/solver_options.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/laser/censi_consensus.h>
#include <calib/solvers/laser/laser_jitter_refit.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

namespace calib {
namespace {

// The unwhitened errors of every dataset's intervals (LaserProblem::Errors).
using DatasetErrors = std::vector<std::vector<Eigen::Vector3d>>;

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string IntervalName(const LaserInterval& interval, size_t index) {
  std::string name = interval.record > 0 ? "record " + std::to_string(interval.record)
                                         : "interval " + std::to_string(index + 1);
  if (interval.line > 0) name += " (line " + std::to_string(interval.line) + ")";
  return name;
}

// Beyond this, no unit explains a value (DropImplausibleIntervals drops such records on reading).
constexpr double kLargestValue = 1e9;

// A relative change of the noise level below which another fit would move the estimate by a
// negligible fraction of its sigma.
constexpr double kNoiseRefitChange = 0.01;

Eigen::Matrix3d DiagonalSqrtInformation(const Eigen::Vector3d& sigma) {
  return sigma.cwiseInverse().asDiagonal();
}

// Above this many intervals the refinement starts from a fit to a subset of this size.
constexpr size_t kWarmStartAbove = 100000;
constexpr size_t kWarmStartSubset = 50000;

// What a sequence of solves did: iterations summed, and whether the last one converged.
struct SolveOutcome {
  int iterations = 0;
  bool converged = true;
  std::string not_converged;  // Why the last solve stopped, when it did not converge.
  // Each log's errors at the final parameters, when the last noise estimate computed them.
  DatasetErrors errors;
  std::vector<Eigen::Vector3d> noise_sigma;  // Each log's last noise level (at those parameters).
};

// The convex stage between two calibrations of one log: `given` (may be null) replaces the
// first solve where it applies; `done` (may be empty) is told the first solve's convex stage.
struct ConvexStageHandOff {
  const LaserConvexStage* given = nullptr;
  std::function<void(const LaserConvexStage&)> done;
};

// A solve's iterations added to *outcome, and how it ended.
void AddSolve(const ceres::Solver::Summary& summary, SolveOutcome* outcome) {
  outcome->iterations += static_cast<int>(summary.iterations.size());
  outcome->converged = Converged(summary);
  outcome->not_converged = outcome->converged ? "" : NotConvergedText("the refinement", summary);
}

// The first solve of RefineWithNoise, or the given convex stage in its place.
Status FirstSolve(const LaserCalibrationOptions& options, const ConvexStageHandOff& hand_off,
                  LaserProblem* problem, SolveOutcome* outcome) {
  LaserConvexStage stage;
  stage.start = problem->calibration();
  stage.refinement = options.refinement;
  for (size_t d = 0; d < problem->num_datasets(); ++d) {
    stage.noise_sigma.push_back(problem->sqrt_information(d).diagonal().cwiseInverse());
  }
  const LaserConvexStage* given = hand_off.given;
  if (given != nullptr && !problem->solves_in_stages() &&
      given->Replaces(stage.start, stage.noise_sigma, options.refinement)) {
    problem->set_calibration(given->estimate);
    outcome->iterations += given->iterations;
    outcome->converged = given->converged;
    outcome->not_converged = given->not_converged;
    return Status::Ok();
  }
  std::function<void(const ceres::Solver::Summary&)> after_convex_stage;
  if (hand_off.done) {
    after_convex_stage = [&](const ceres::Solver::Summary& first) {
      SolveOutcome first_outcome;
      AddSolve(first, &first_outcome);
      stage.estimate = problem->calibration();
      stage.iterations = first_outcome.iterations;
      stage.converged = first_outcome.converged;
      stage.not_converged = first_outcome.not_converged;
      hand_off.done(stage);
    };
  }
  ceres::Solver::Summary summary;
  CALIB_RETURN_IF_ERROR(problem->Solve(&summary, after_convex_stage));
  AddSolve(summary, outcome);
  return Status::Ok();
}

// Fits, re-estimates each log's noise from the residuals (unless fixed), and fits again while
// the noise level still moves enough to shift the weights.
StatusOr<SolveOutcome> RefineWithNoise(const LaserCalibrationOptions& options,
                                       const ConvexStageHandOff& hand_off, LaserProblem* problem,
                                       const std::function<void(const std::string&)>& report) {
  SolveOutcome outcome;
  // Whitens each log by its robust noise level; returns the largest relative change. The errors
  // after the last solve are kept for the checks that follow (the same parameters).
  const auto estimate_noise = [&]() {
    double change = 0.0;
    outcome.errors.clear();
    outcome.noise_sigma.clear();
    for (size_t d = 0; d < problem->num_datasets(); ++d) {
      if (!options.noise_sigma) outcome.errors.push_back(problem->Errors(d));
      const Eigen::Vector3d sigma =
          options.noise_sigma
              ? *options.noise_sigma
              : RobustNoiseSigma(outcome.errors.back(), options.refinement.num_threads);
      const Eigen::Vector3d old_sigma = problem->sqrt_information(d).diagonal().cwiseInverse();
      change = std::max(change, ((sigma - old_sigma).cwiseQuotient(sigma)).cwiseAbs().maxCoeff());
      problem->SetSqrtInformation(d, DiagonalSqrtInformation(sigma));
      outcome.noise_sigma.push_back(sigma);
    }
    return change;
  };
  estimate_noise();
  outcome.errors.clear();  // Before the solve: not the final parameters'.
  for (int round = 0; round < std::max(1, options.noise_rounds); ++round) {
    const int before = outcome.iterations;
    if (round == 0) {
      CALIB_RETURN_IF_ERROR(FirstSolve(options, hand_off, problem, &outcome));
    } else {
      ceres::Solver::Summary summary;
      CALIB_RETURN_IF_ERROR(problem->Solve(&summary));
      AddSolve(summary, &outcome);
    }
    report("refinement round " + std::to_string(round + 1) + ": " +
           std::to_string(outcome.iterations - before) + " iterations");
    if (options.noise_sigma || estimate_noise() < kNoiseRefitChange) break;
  }
  return outcome;
}

// Every `stride`-th interval of each log (the warm start's subset).
std::vector<std::vector<LaserInterval>> EvenSubsets(
    const std::vector<const std::vector<LaserInterval>*>& logs, size_t stride) {
  std::vector<std::vector<LaserInterval>> subsets(logs.size());
  for (size_t d = 0; d < logs.size(); ++d) subsets[d] = EveryNthInterval(*logs[d], stride);
  return subsets;
}

// The refinement's seed: the paper's trimmed closed form. Slips can drag the plain one far
// enough (at a few hundred noisy intervals with 20 % slips) that LM settles in a wrong basin with
// near-zero radii. When the trimming fails (it can remove the few turns a log has) the plain one
// is used, and a warning says so.
void SeedFromTrimmedClosedForm(const std::vector<LaserInterval>& intervals,
                               const ConsensusScreen* screen, LaserCalibrationResult* result) {
  const StatusOr<TrimmedClosedFormResult> trimmed = CensiClosedFormTrimmed(intervals, {}, screen);
  result->seed_trimmed = trimmed.ok();
  if (trimmed.ok()) {
    result->closed_form_trimmed = trimmed->estimate;
    return;
  }
  result->closed_form_trimmed = result->closed_form;
  result->warnings.push_back("the trimmed closed form failed (" + trimmed.message() +
                             "): the refinement started from the closed form on all intervals");
}

// The closed form without the intervals that disagree grossly with the consensus, named in a
// warning; on all intervals when the screen leaves too little motion (then its error, if any).
// The screen goes to *screen (the trimmed closed form's starts from it).
Status ClosedFormWithoutGross(const std::vector<LaserInterval>& intervals,
                              const ConsensusScreen* given, ConsensusScreen* screen_out,
                              LaserCalibrationResult* result) {
  ConsensusScreen& screen = *screen_out;
  const bool reuse = given != nullptr && given->kept.size() == intervals.size();
  if (reuse) screen = *given;
  const StatusOr<CensiClosedFormResult> screened =
      reuse ? ClosedFormOnKept(intervals, screen) : CensiClosedFormScreened(intervals, &screen);
  if (screened.ok() && screen.outliers() == 0) {
    result->closed_form = *screened;  // Every interval kept: the closed form on all of them.
    return Status::Ok();
  }
  if (!screened.ok() || screen.outliers() == 0) {
    CALIB_ASSIGN_OR_RETURN(result->closed_form, CensiClosedForm(intervals));
    return Status::Ok();
  }
  result->closed_form = *screened;
  result->gross_intervals = screen.outliers();
  // Not a warning: scan-matcher failures are common, and the robust fit counts its inliers.
  result->gross_note = std::to_string(screen.outliers()) + " of " +
                       std::to_string(intervals.size()) +
                       " intervals disagree grossly with the rest of the log (first: " +
                       IntervalName(intervals[static_cast<size_t>(screen.first_outlier)],
                                    static_cast<size_t>(screen.first_outlier)) +
                       "): the closed form leaves them out, and the robust fit down-weights them";
  return Status::Ok();
}

// The closed forms' share of a result (ClosedFormWithoutGross, SeedFromTrimmedClosedForm), from
// a calibration of the same log; its warnings so far are the trimming's.
void CopyClosedForms(const LaserCalibrationResult& from, LaserCalibrationResult* result) {
  result->closed_form = from.closed_form;
  result->gross_intervals = from.gross_intervals;
  result->gross_note = from.gross_note;
  result->closed_form_trimmed = from.closed_form_trimmed;
  result->seed_trimmed = from.seed_trimmed;
  result->warnings = from.warnings;
}

// Fewer moving intervals than this per unknown give neither an estimate nor error bars worth
// reporting (3 intervals fit 6 unknowns with 3 residual degrees of freedom: σ is then noise).
constexpr int kMinIntervalsPerUnknown = 4;

Status CheckEnoughIntervals(const LaserMotionCensus& census) {
  const int moving = census.total - census.still;
  const int needed = kMinIntervalsPerUnknown * kNumLaserParams;
  if (moving >= needed) return Status::Ok();
  return Status::NotObservable(
      "only " + std::to_string(moving) + " moving interval(s) (of " + std::to_string(census.total) +
      ") for the six unknowns r_l, r_r, b and the sensor's x, y, " + "θ: at least " +
      std::to_string(needed) + ", " + std::to_string(kMinIntervalsPerUnknown) +
      " per unknown, are needed for an estimate and its error bars; record a longer log with " +
      "turns and arcs");
}

// Whether the fit can be relied on: most intervals gross (the robust loss then follows them), or
// inliers that lack the motion the parameters need, make the result unreliable.
void JudgeInliers(const LaserProblem& problem, const DatasetErrors& errors,
                  const std::vector<LaserInterval>& joined, LaserCalibrationResult* result) {
  Eigen::MatrixXd whitened(result->samples, 3);
  std::vector<bool> inlier;
  Eigen::Index row = 0;
  for (size_t d = 0; d < problem.num_datasets(); ++d) {
    for (const Eigen::Vector3d& e : errors[d]) {
      whitened.row(row++) = (problem.sqrt_information(d) * e).transpose();
    }
    inlier.insert(inlier.end(), result->is_inlier[d].begin(), result->is_inlier[d].end());
  }
  result->outlier_share = GrossOutlierShare(whitened);
  if (result->outlier_share > kMaxTrustedOutlierShare) {
    result->unreliable.push_back(
        Format("%.0f %% of the intervals disagree grossly with the fit, more than the %.0f %% a "
               "robust fit survives: the estimate may follow them; check the wheel-speed signs, "
               "units and the scan matcher",
               100.0 * result->outlier_share, 100.0 * kMaxTrustedOutlierShare));
  }
  const std::string missing = DescribeMissingLaserMotion(CountLaserMotion(joined, &inlier));
  if (!missing.empty()) {
    result->unreliable.push_back("the intervals that agree with the fit do not determine it: " +
                                 missing);
  }
  result->warnings.insert(result->warnings.end(), result->unreliable.begin(),
                          result->unreliable.end());
}

// Inliers of each log (squared whitened residual below the cut) and their noise level. A log
// without inliers keeps the robust level of all its intervals, with a warning (never NaN).
void ClassifyInliers(const LaserProblem& problem, const DatasetErrors& all_errors,
                     double inlier_chi2, LaserCalibrationResult* result) {
  for (size_t d = 0; d < problem.num_datasets(); ++d) {
    const std::vector<Eigen::Vector3d>& errors = all_errors[d];
    const Eigen::Matrix3d& sqrt_information = problem.sqrt_information(d);
    std::vector<bool> inlier(errors.size());
    Eigen::Vector3d sum_sq = Eigen::Vector3d::Zero();
    int count = 0;
    for (size_t k = 0; k < errors.size(); ++k) {
      inlier[k] = (sqrt_information * errors[k]).squaredNorm() < inlier_chi2;
      if (inlier[k]) {
        sum_sq += errors[k].cwiseAbs2();
        ++count;
      }
    }
    result->inliers += count;
    if (count > 0) {
      result->noise_sigma.push_back((sum_sq / count).cwiseSqrt());
    } else {
      result->noise_sigma.push_back(RobustNoiseSigma(errors));
      result->warnings.push_back(
          (problem.num_datasets() > 1 ? "log " + std::to_string(d + 1) + ": " : std::string()) +
          "no interval agrees with the model: its scan noise is the robust level of all "
          "intervals");
    }
    result->is_inlier.push_back(std::move(inlier));
  }
}

// Refines on an evenly spread subset first (every `stride`-th interval): its optimum lies within a
// few full-data sigmas of the final one, so the full problem then converges in a few iterations.
// Updates `initial`, and gives each log's noise level and the iterations spent.
Status WarmStart(const std::vector<const std::vector<LaserInterval>*>& logs, size_t stride,
                 const LaserCalibrationOptions& options,
                 const std::function<void(const std::string&)>& report, LaserCalibration* initial,
                 std::vector<Eigen::Vector3d>* initial_sigma, int* iterations) {
  const std::vector<std::vector<LaserInterval>> subsets = EvenSubsets(logs, stride);
  std::vector<LaserDataset> subset_datasets;
  size_t total = 0;
  for (const auto& subset : subsets) {
    subset_datasets.push_back(LaserDataset{&subset, Eigen::Matrix3d::Identity()});
  }
  for (const auto* log : logs) total += log->size();
  LaserProblem warm(subset_datasets, *initial, options.refinement);
  CALIB_ASSIGN_OR_RETURN(const SolveOutcome warm_outcome,
                         RefineWithNoise(options, {}, &warm, report));
  *iterations += warm_outcome.iterations;
  *initial = warm.calibration();
  for (size_t d = 0; d < logs.size(); ++d) {
    initial_sigma->push_back(warm.sqrt_information(d).diagonal().cwiseInverse());
  }
  report("warm start on " + std::to_string(total / stride) + " intervals done");
  return Status::Ok();
}

// Options under which two solves from the same start and whitening are the same solve.
bool SameRefinement(const LaserRefinementOptions& a, const LaserRefinementOptions& b) {
  // num_threads: the fused passes split their sums the same way on any number of threads.
  return a.loss == b.loss && a.loss_scale == b.loss_scale && a.max_iterations == b.max_iterations &&
         a.per_interval_blocks == b.per_interval_blocks &&
         (!a.per_interval_blocks || a.num_threads == b.num_threads);
}

}  // namespace

bool LaserConvexStage::Replaces(const LaserCalibration& from,
                                const std::vector<Eigen::Vector3d>& sigma,
                                const LaserRefinementOptions& options) const {
  return from.ToVector() == start.ToVector() && sigma == noise_sigma &&
         SameRefinement(options, refinement);
}

Status ValidateLaserIntervals(const std::vector<LaserInterval>& intervals) {
  if (intervals.empty()) return Status::InvalidInput("the log holds no intervals");
  for (size_t k = 0; k < intervals.size(); ++k) {
    const LaserInterval& interval = intervals[k];
    if (!(interval.duration_s > 0.0) || !std::isfinite(interval.duration_s)) {
      return Status::InvalidInput(IntervalName(interval, k) + ": T must be positive and finite");
    }
    if (!std::isfinite(interval.left_speed) || !std::isfinite(interval.right_speed) ||
        !interval.sensor_motion.allFinite()) {
      return Status::InvalidInput(IntervalName(interval, k) +
                                  ": wheel speeds and sm must be finite");
    }
    // The readers drop such records; a log built in memory is refused before any solver sees it.
    const double largest =
        std::max({interval.duration_s, std::abs(interval.left_speed),
                  std::abs(interval.right_speed), interval.sensor_motion.cwiseAbs().maxCoeff()});
    if (largest > kLargestValue) {
      return Status::InvalidInput(IntervalName(interval, k) + ": a value of " + Num(largest) +
                                  " is beyond what any unit explains (1e9)");
    }
    for (const WheelStep& step : interval.steps) {
      if (!std::isfinite(step.left_rad) || !std::isfinite(step.right_rad)) {
        return Status::InvalidInput(IntervalName(interval, k) + ": wheel steps must be finite");
      }
    }
  }
  return Status::Ok();
}

StatusOr<LaserCalibrationResult> CalibrateLaser(const std::vector<LaserInterval>& intervals,
                                                const LaserCalibrationOptions& options) {
  return CalibrateLaserJoint({&intervals}, options);
}

StatusOr<LaserCalibrationResult> CalibrateLaserJoint(
    const std::vector<const std::vector<LaserInterval>*>& logs,
    const LaserCalibrationOptions& options) {
  const auto report = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  if (logs.empty()) return Status::InvalidInput("no logs to calibrate");
  std::vector<LaserInterval> all;
  for (size_t i = 0; i < logs.size(); ++i) {
    CALIB_RETURN_IF_ERROR(ValidateLaserIntervals(*logs[i]).Prefixed(
        logs.size() > 1 ? "log " + std::to_string(i + 1) + ": " : ""));
    if (logs.size() > 1) all.insert(all.end(), logs[i]->begin(), logs[i]->end());
  }
  const std::vector<LaserInterval>& joined = logs.size() > 1 ? all : *logs[0];

  LaserCalibrationResult result;
  result.samples = static_cast<int>(joined.size());
  result.census = CountLaserMotion(joined);
  CALIB_RETURN_IF_ERROR(CheckEnoughIntervals(result.census));

  auto start = std::chrono::steady_clock::now();
  const size_t total = joined.size();
  const size_t stride = (total + kWarmStartSubset - 1) / kWarmStartSubset;
  std::shared_ptr<const LaserCalibrationResult> awaited;
  if (!options.closed_forms && options.await_closed_forms) awaited = options.await_closed_forms();
  const LaserCalibrationResult* given_closed_forms =
      options.closed_forms ? options.closed_forms.get() : awaited.get();
  if (given_closed_forms != nullptr && logs.size() == 1 &&
      given_closed_forms->samples == result.samples) {
    CopyClosedForms(*given_closed_forms, &result);
  } else {
    ConsensusScreen screen;
    const ConsensusScreen* given = logs.size() == 1 ? options.consensus_screen.get() : nullptr;
    CALIB_RETURN_IF_ERROR(ClosedFormWithoutGross(joined, given, &screen, &result));
    // On huge logs an evenly spread subset suffices for a seed.
    if (total > kWarmStartAbove) {
      SeedFromTrimmedClosedForm(EvenSubsets({&joined}, stride).front(), nullptr, &result);
    } else {
      SeedFromTrimmedClosedForm(joined, &screen, &result);
    }
  }
  result.closed_form_seconds = SecondsSince(start);
  report("closed form done in " + std::to_string(result.closed_form_seconds) + " s");

  start = std::chrono::steady_clock::now();
  LaserCalibration initial = result.closed_form_trimmed.calibration;
  if (!initial.ToVector().allFinite() || !(initial.odometry.left_radius_m > 0.0) ||
      !(initial.odometry.right_radius_m > 0.0) || !(initial.odometry.wheelbase_m > 0.0)) {
    return Status::NotObservable(
        "the closed form gave no usable seed: the data do not fit a "
        "differential-drive robot");
  }
  std::vector<Eigen::Vector3d> initial_sigma;
  if (total > kWarmStartAbove) {
    CALIB_RETURN_IF_ERROR(
        WarmStart(logs, stride, options, report, &initial, &initial_sigma, &result.iterations));
  }
  std::vector<LaserDataset> datasets;
  for (size_t d = 0; d < logs.size(); ++d) {
    datasets.push_back(LaserDataset{logs[d], initial_sigma.empty()
                                                 ? Eigen::Matrix3d::Identity()
                                                 : DiagonalSqrtInformation(initial_sigma[d])});
  }
  LaserProblem problem(datasets, initial, options.refinement);
  // The warm start ended under the redescending loss: the full problem starts there directly.
  if (!initial_sigma.empty()) problem.Redescend();
  result.loss = problem.LossDescription();
  ConvexStageHandOff hand_off;
  if (given_closed_forms != nullptr && given_closed_forms->convex_stage && logs.size() == 1 &&
      given_closed_forms->samples == result.samples) {
    hand_off.given = &*given_closed_forms->convex_stage;
  }
  if (options.closed_forms_done && logs.size() == 1 && problem.solves_in_stages()) {
    hand_off.done = [&](const LaserConvexStage& stage) {
      result.convex_stage = stage;
      options.closed_forms_done(result);
    };
  } else if (options.closed_forms_done) {
    options.closed_forms_done(result);
  }
  CALIB_ASSIGN_OR_RETURN(SolveOutcome outcome,
                         RefineWithNoise(options, hand_off, &problem, report));
  result.iterations += outcome.iterations;
  result.converged = outcome.converged;
  if (!outcome.converged) result.warnings.push_back(outcome.not_converged);
  result.estimate = problem.calibration();
  result.robust_noise_sigma = std::move(outcome.noise_sigma);
  result.refinement_seconds = SecondsSince(start);
  // The errors at the estimate (the refinement's last noise estimate's), one pass for the inlier
  // flags, the covariance's loss correction and the judgement of the inliers; released before the
  // consistency check.
  DatasetErrors errors = std::move(outcome.errors);
  if (errors.size() != problem.num_datasets()) {
    errors.clear();
    for (size_t d = 0; d < problem.num_datasets(); ++d) errors.push_back(problem.Errors(d));
  }
  ClassifyInliers(problem, errors, options.inlier_chi2, &result);
  if (options.estimate_only) return result;

  // The jitter first: when it is significant the refit replaces the covariance.
  bool jitter_refit = false;
  double jitter_seconds = 0.0;
  if (options.interval_jitter) {
    start = std::chrono::steady_clock::now();
    jitter_refit = EstimateBaseFitJitter(logs, options, &result, &errors);
    jitter_seconds = SecondsSince(start);
  }
  if (!jitter_refit) {
    result.refinement_seconds += jitter_seconds;
    start = std::chrono::steady_clock::now();
    // The fused problem hands ceres::Covariance a 7×6 Jacobian whatever N: one pass, no switch
    // to another estimator on long logs.
    CALIB_ASSIGN_OR_RETURN(const CorrectedCovariance<LaserParamMatrix> covariance,
                           problem.Covariance(&errors));
    result.covariance = covariance.covariance;
    result.covariance_scale = covariance.kappa;
    result.stddev = result.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
    result.covariance_seconds = SecondsSince(start);
    report("covariance done in " + std::to_string(result.covariance_seconds) + " s");
    result.observability =
        AnalyzeLaserObservability(result.covariance, result.estimate, result.census);
  } else {
    start = std::chrono::steady_clock::now();
    CALIB_RETURN_IF_ERROR(RefitWithIntervalJitter(logs, options, &result));
    jitter_seconds += SecondsSince(start);
    result.refinement_seconds += jitter_seconds - result.covariance_seconds;
  }
  if (options.interval_jitter) {
    report("interval jitter done in " + std::to_string(jitter_seconds) + " s");
  }
  start = std::chrono::steady_clock::now();
  JudgeInliers(problem, errors, joined, &result);
  DatasetErrors().swap(errors);
  result.consistency = CheckLaserConsistencyJoint(logs, result.estimate, result.covariance,
                                                  result.noise_sigma, result.is_inlier);
  report("inlier and consistency checks done in " + std::to_string(SecondsSince(start)) + " s");
  result.warnings.insert(result.warnings.end(), result.consistency.warnings.begin(),
                         result.consistency.warnings.end());
  // The solver's warnings join the observability's, which the report prints.
  result.observability.warnings.insert(result.observability.warnings.end(), result.warnings.begin(),
                                       result.warnings.end());
  return result;
}

}  // namespace calib
