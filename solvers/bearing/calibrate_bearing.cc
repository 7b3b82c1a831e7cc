#include <calib/core/bearing/bearing_log_io.h>
#include <calib/solvers/bearing/bearing_consistency.h>
#include <calib/solvers/bearing/bearing_input_checks.h>
#include <calib/solvers/bearing/bearing_text.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <calib/solvers/bearing/calibrate_bearing_internal.h>
#include <calib/solvers/common/outlier_share.h>
#include <calib/solvers/common/solver_options.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <utility>

namespace calib {
namespace {

// A variance component is re-estimated only from at least this many degrees of freedom.
constexpr double kMinRedundancy = 2.0;
constexpr double kMinOdometryRedundancy = 0.5;
// Bounds of the estimated noise levels (rad, m^½).
constexpr double kMinSigma = 1e-8, kMaxSigma = 0.5, kMinK = 1e-8;
// The noise rounds start from the fit's robust scale when it is below this share of σβ.
// (Not on noise-free logs: below kMinStartSigma (rad) the bearings' weights swamp the odometry.)
constexpr double kStartBelow = 0.8, kMinStartSigma = 1e-6;

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

using bearing_calibration::BearingMask;
using bearing_calibration::Progress;

// The bearings the seeds use (the closed form and the search are least squares): those within
// the cut of their neighbours in time, relative to the larger of the log's and the run's scatter
// and never below 2° (only gross outliers matter to the seeds). A run that would keep fewer than
// 8 of its bearings keeps them all.
BearingMask SeedSelection(const BearingLog& log, const BearingConsistency& consistency,
                          double cut_factor, int* excluded) {
  BearingMask keep(log.runs.size());
  for (size_t i = 0; i < log.runs.size(); ++i) {
    const size_t n = log.runs[i].bearings.size();
    const double cut =
        std::max(cut_factor * std::max(consistency.sigma_rad, consistency.run_sigma_rad[i]),
                 2.0 * M_PI / 180.0);
    keep[i].resize(n);
    size_t kept = 0;
    for (size_t j = 0; j < n; ++j) {
      keep[i][j] = std::abs(consistency.z[i][j]) <= cut;
      kept += keep[i][j];
    }
    if (kept >= std::min<size_t>(8, n)) {
      *excluded += static_cast<int>(n - kept);
    } else {
      keep[i].assign(n, true);
    }
  }
  return keep;
}

// The seeds in turn, and what came of them.
struct SeedChoice {
  std::unique_ptr<BearingProblem> problem;
  std::vector<Eigen::Vector2d> landmarks;
  ceres::Solver::Summary summary;
  std::string rejected;  // Why seeds were rejected, "; "-separated.
};

// The closed form on the circular runs (without the metric set when the distance is given for a
// run that is not a circle); records it, or why it does not apply, in `result`.
std::optional<BearingParams> ClosedFormSeed(const BearingLog& log, const BearingMask& keep,
                                            const BearingCalibrationOptions& options,
                                            const std::string& source,
                                            BearingCalibrationResult* result) {
  MartinelliOptions cf_options = options.closed_form;
  cf_options.skip_non_circular_runs = true;
  StatusOr<MartinelliEstimate> cf = MartinelliClosedFormOf(log, &keep, cf_options);
  if (!cf.ok()) {
    result->closed_form_message = source + ": " + cf.message();
    return std::nullopt;
  }
  result->has_closed_form = true;
  result->closed_form = *cf;
  return cf->params;
}

// The adjustment from a seed, kept when it explains the bearings as well as their neighbours
// agree (its residuals' robust scale within max_fit_over_scatter of theirs); otherwise it led
// to a wrong minimum, and the reason goes to `choice->rejected`.
bool AdjustFromSeed(const BearingLog& log, const BearingMask& keep, const BearingParams& seed,
                    BearingSeedMethod method, const BearingNoise& noise, double scatter_rad,
                    const BearingCalibrationOptions& options, const Progress& progress,
                    SeedChoice* choice, BearingCalibrationResult* result) {
  StatusOr<std::vector<Eigen::Vector2d>> landmarks = SeedLandmarks(log, seed, &keep);
  if (!landmarks.ok()) {
    AppendReason(&choice->rejected, landmarks.message());
    return false;
  }
  auto candidate = std::make_unique<BearingProblem>(
      log, seed, DeadReckonedPoses(log, seed, *landmarks), noise, options.adjustment);
  const Status solved = candidate->Solve(&choice->summary);
  if (!solved.ok()) {
    AppendReason(&choice->rejected, solved.message());
    return false;
  }
  const double fit = RobustSigma(candidate->BearingErrors());
  if (!(fit <= options.max_fit_over_scatter * scatter_rad + 1e-6)) {
    const bool closed_form = method == BearingSeedMethod::kClosedForm;
    const std::string why = "from the " + std::string(closed_form ? "closed-form" : "search") +
                            " seed the adjustment leaves bearing residuals of " +
                            Num(fit * 180.0 / M_PI, 3) + "° where neighbouring bearings agree to " +
                            Num(scatter_rad * 180.0 / M_PI, 3) + "°";
    if (closed_form) result->closed_form_message = why;
    AppendReason(&choice->rejected, why);
    progress(why);
    return false;
  }
  choice->problem = std::move(candidate);
  choice->landmarks = std::move(*landmarks);
  result->seed = seed;
  result->seed_method = method;
  result->iterations = static_cast<int>(choice->summary.iterations.size());
  return true;
}

// The closed form (circular runs) first, then the search; NotObservable when neither explains
// the bearings.
StatusOr<SeedChoice> ChooseSeed(const BearingLog& log, const BearingMask& keep,
                                const BearingNoise& noise, double scatter_rad,
                                const BearingCalibrationOptions& options, const Progress& progress,
                                const std::string& source, BearingCalibrationResult* result) {
  SeedChoice choice;
  if (options.use_closed_form) {
    const std::optional<BearingParams> seed = ClosedFormSeed(log, keep, options, source, result);
    if (seed && AdjustFromSeed(log, keep, *seed, BearingSeedMethod::kClosedForm, noise, scatter_rad,
                               options, progress, &choice, result)) {
      return choice;
    }
  }
  progress("searching for a seed");
  BearingSearchOptions search = options.search;  // On the threads the adjustment may use.
  search.num_threads = std::max(search.num_threads, options.adjustment.num_threads);
  StatusOr<BearingParams> searched = SearchBearingSeedOf(log, &keep, search);
  if (!searched.ok()) {
    AppendReason(&choice.rejected, searched.message());
  } else if (AdjustFromSeed(log, keep, *searched, BearingSeedMethod::kSearch, noise, scatter_rad,
                            options, progress, &choice, result)) {
    return choice;
  }
  std::string why = choice.rejected;  // Holds the closed form's rejection when it ran.
  if (!result->has_closed_form && !result->closed_form_message.empty()) {
    why = "the closed form does not apply: " + result->closed_form_message +
          (why.empty() ? "" : "; " + why);
  }
  return Status::NotObservable(source + ": no calibration explains the bearings" +
                               (why.empty() ? "" : " (" + why + ")"));
}

// Flags the bearings within the inlier cut (√χ² σβ) of the adjustment as it stands.
BearingMask ClassifyInliers(const BearingProblem& problem, double cut) {
  BearingMask inlier;
  for (const auto& run : problem.BearingErrors()) {
    std::vector<bool> flags;
    for (double e : run) flags.push_back(std::abs(e) <= cut * problem.noise().bearing_sigma_rad);
    inlier.push_back(flags);
  }
  return inlier;
}

// The next noise levels from the variance components (those the options leave to the data).
BearingNoise NextNoise(const BearingVarianceComponents& vc, const BearingNoise& current,
                       double kept_variance, const BearingCalibrationOptions& options,
                       BearingCalibrationResult* result) {
  BearingNoise next = current;
  if (result->bearing_sigma_estimated && vc.bearing_redundancy >= kMinRedundancy) {
    next.bearing_sigma_rad =
        std::clamp(std::sqrt(vc.bearing_sum_sq_rad2 / vc.bearing_redundancy / kept_variance),
                   kMinSigma, kMaxSigma);
  }
  if (result->encoder_k_estimated && vc.odometry_redundancy >= kMinOdometryRedundancy) {
    // A K too small makes the odometry rigid and leaves it few degrees of freedom, so that it
    // would never be corrected: the update runs from half a degree of freedom on. The fixed
    // point K = K·√(Σ‖L·e‖²/r) is approached slowly (the redundancy grows with K), so each
    // step is doubled in log K (over-relaxation), and kept within a factor of 3.
    const double ratio = vc.odometry_sum_sq / vc.odometry_redundancy;
    result->encoder_k_estimate = next.encoder_k * std::sqrt(ratio);
    next.encoder_k = std::max(
        {kMinK, options.encoder_noise_k_floor, next.encoder_k * std::clamp(ratio, 1.0 / 3.0, 3.0)});
  }
  return next;
}

// Covariance, and the metric set when a distance is known. When K comes from the data (above its
// floor), from few degrees of freedom r, the covariance takes K at the upper end of its one-sigma
// range, K²·(1 + √(2/r)): the uncertainty of K itself must not make sigmas too small.
Status ComputeCovariance(const BearingLog& log, const BearingCalibrationOptions& options,
                         BearingProblem* problem, BearingCalibrationResult* result) {
  BearingNoise reported = problem->noise();
  if (result->encoder_k_estimated && result->odometry_redundancy >= kMinRedundancy &&
      reported.encoder_k > options.encoder_noise_k_floor) {
    reported.encoder_k *= std::sqrt(1.0 + std::sqrt(2.0 / result->odometry_redundancy));
    problem->SetNoise(reported);
  }
  result->covariance_encoder_k = reported.encoder_k;
  CALIB_ASSIGN_OR_RETURN(const BearingEstimateCovariance cov,
                         EstimateCovariance(*problem, log, result->estimate));
  result->covariance = cov.covariance;
  result->covariance_scale = cov.kappa;
  result->has_metric = cov.has_metric;
  if (cov.has_metric) {
    result->metric = cov.metric;
    result->metric_covariance = cov.metric_covariance;
    result->metric_stddev = result->metric_covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  }
  result->stddev = result->covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  return Status::Ok();
}

// A parameter the log barely determines is a warning with its σ; one it does not determine at
// all (σ beyond the undetermined limits, or not finite) is an error, not a number.
Status CheckDetermined(const BearingCalibrationOptions& options, BearingCalibrationResult* result) {
  const BearingParamVector value = ToVector(result->estimate);
  std::string weak, undetermined;
  for (int i = 0; i < kNumBearingParams; ++i) {
    const bool angle = i == kBearingPhi || i == kBearingPsi;
    const double scale = angle ? 1.0 : std::abs(value(i));
    const double warn =
        scale * (angle ? options.max_angle_stddev_rad : options.max_relative_stddev);
    const double refuse = scale * (angle ? options.undetermined_angle_stddev_rad
                                         : options.undetermined_relative_stddev);
    const double sigma = result->stddev(i);
    const std::string entry = std::string(kBearingParamNames[i]) + " (σ = " + Num(sigma, 3) +
                              (angle ? " rad" : ", " + Num(100.0 * sigma / scale, 2) + " %") + ")";
    if (!(sigma <= refuse)) {
      undetermined += (undetermined.empty() ? "" : ", ") + entry;
    } else if (!(sigma <= warn)) {
      weak += (weak.empty() ? "" : ", ") + entry;
    }
  }
  constexpr const char* kNeeds =
      "it needs circular runs at three or more distinct wheel-speed ratios, or runs whose "
      "curvature varies, with the landmark in view";
  if (!undetermined.empty()) {
    return Status::NotObservable("the log does not determine " + undetermined + ": " + kNeeds);
  }
  if (!weak.empty()) {
    result->warnings.push_back("poorly determined: " + weak +
                               "; the other parameters are sound, but do not deploy these "
                               "without more data (" +
                               kNeeds + ")");
  }
  return Status::Ok();
}

// Fewer bearings than this per unknown (the five calibration parameters and each run's start
// pose) give neither an estimate nor error bars worth reporting.
constexpr int kMinBearingsPerUnknown = 4;

Status CheckEnoughBearings(const BearingLog& log) {
  size_t bearings = 0;
  for (const BearingRun& run : log.runs) bearings += run.bearings.size();
  const size_t unknowns = 5 + 3 * log.runs.size();
  if (bearings >= kMinBearingsPerUnknown * unknowns) return Status::Ok();
  return Status::NotObservable(
      "only " + std::to_string(bearings) + " bearings for " + std::to_string(unknowns) +
      " unknowns (φ, ψ, η, δ, ξ and each run's start pose): at least " +
      std::to_string(kMinBearingsPerUnknown * unknowns) + ", " +
      std::to_string(kMinBearingsPerUnknown) +
      " per unknown, are needed for an estimate and its error bars; record longer runs");
}

// Most bearings gross: the robust loss then follows them, and the result is unreliable.
void JudgeOutliers(BearingCalibrationResult* result) {
  size_t n = 0;
  for (const std::vector<double>& run : result->residuals_rad) n += run.size();
  Eigen::MatrixXd residuals(static_cast<Eigen::Index>(n), 1);
  Eigen::Index row = 0;
  for (const std::vector<double>& run : result->residuals_rad) {
    for (const double r : run) residuals(row++, 0) = r;
  }
  result->outlier_share = GrossOutlierShare(residuals);
  if (result->outlier_share <= kMaxTrustedOutlierShare) return;
  char text[256];
  std::snprintf(text, sizeof(text),
                "%.0f %% of the bearings disagree grossly with the fit, more than the %.0f %% a "
                "robust fit survives: the estimate may follow them; check the bearing sign, unit "
                "and the landmark detector",
                100.0 * result->outlier_share, 100.0 * kMaxTrustedOutlierShare);
  result->unreliable.push_back(text);
  result->warnings.push_back(text);
}

void SummarizeRuns(const BearingLog& log, const BearingProblem& problem, const BearingMask& inlier,
                   BearingCalibrationResult* result) {
  for (size_t i = 0; i < log.runs.size(); ++i) {
    BearingRunSummary s;
    s.run = log.runs[i].id;
    s.bearings = static_cast<int>(log.runs[i].bearings.size());
    double sum = 0.0;
    for (size_t j = 0; j < inlier[i].size(); ++j) {
      if (!inlier[i][j]) continue;
      ++s.inliers;
      sum += result->residuals_rad[i][j] * result->residuals_rad[i][j];
    }
    s.rms_residual_rad = s.inliers > 0 ? std::sqrt(sum / s.inliers) : 0.0;
    s.start_distance = problem.StartDistance(i);
    if (result->has_closed_form) {
      for (const MartinelliRunEstimate& run : result->closed_form.runs) {
        if (run.run == s.run) s.circular = true, s.q = run.q;
      }
    }
    result->samples += s.bearings;
    result->inliers += s.inliers;
    result->runs.push_back(s);
  }
}

// The noise levels the adjustment starts from: given, or K at its floor and σβ as the
// neighbours in time see it.
BearingNoise InitialNoise(const BearingCalibrationOptions& options, double scatter_rad,
                          BearingCalibrationResult* result) {
  BearingNoise noise;
  noise.encoder_k =
      std::max(options.encoder_noise_k.value_or(options.encoder_noise_k_floor), kMinK);
  noise.bearing_sigma_rad =
      options.bearing_sigma_rad.value_or(std::clamp(scatter_rad, kMinSigma, kMaxSigma));
  result->bearing_sigma_estimated = !options.bearing_sigma_rad.has_value();
  result->encoder_k_estimated = !options.encoder_noise_k.has_value();
  return noise;
}

}  // namespace

namespace bearing_calibration {

// Noise levels by variance components, re-solving while they change; returns the final inlier
// flags. `summary` ends as that of the last solve.
StatusOr<BearingMask> EstimateNoise(const BearingCalibrationOptions& options,
                                    const Progress& progress, BearingProblem* problem,
                                    ceres::Solver::Summary* summary,
                                    BearingCalibrationResult* result) {
  const double cut = std::sqrt(options.inlier_chi2);
  const double kept_variance = TruncatedVariance(cut);
  // The rounds have a second, inflated fixed point where gross bearings pass the inlier cut of an
  // inflated σβ, and the neighbours' scatter they start from can lie beyond it (20 % of bearings
  // 6–17° off to one side: a scatter of 3.5° for σβ = 1°, kept, with ψ 13σ off). Well above the
  // fit's own robust scale (its median error, shrunk by the leverages), they start from that
  // instead: from below they rise to the fixed point the inliers make.
  const double robust = RobustSigma(problem->BearingErrors());
  if (!options.bearing_sigma_rad && robust > kMinStartSigma &&
      robust < kStartBelow * problem->noise().bearing_sigma_rad) {
    BearingNoise lower = problem->noise();
    lower.bearing_sigma_rad = robust;
    progress("noise: σβ from the fit's median error, " +
             Num(lower.bearing_sigma_rad * 180.0 / M_PI) + "°, below the neighbours' scatter");
    problem->SetNoise(lower);
    CALIB_RETURN_IF_ERROR(problem->Solve(summary));
    result->iterations += static_cast<int>(summary->iterations.size());
  }
  for (int round = 0; round < options.noise_rounds; ++round) {
    CALIB_ASSIGN_OR_RETURN(const BearingVarianceComponents vc,
                           problem->VarianceComponents(ClassifyInliers(*problem, cut)));
    result->bearing_redundancy = vc.bearing_redundancy;
    result->odometry_redundancy = vc.odometry_redundancy;
    const BearingNoise next = NextNoise(vc, problem->noise(), kept_variance, options, result);
    const double change =
        std::max(std::abs(next.bearing_sigma_rad / problem->noise().bearing_sigma_rad - 1.0),
                 std::abs(next.encoder_k / problem->noise().encoder_k - 1.0));
    progress("noise round " + std::to_string(round + 1) + ": σβ = " +
             Num(next.bearing_sigma_rad * 180.0 / M_PI) + "°, K = " + Num(next.encoder_k));
    if (change < options.noise_tolerance) break;
    problem->SetNoise(next);
    problem->Relinearize();
    CALIB_RETURN_IF_ERROR(problem->Solve(summary));
    result->iterations += static_cast<int>(summary->iterations.size());
    ++result->noise_rounds;
  }
  return ClassifyInliers(*problem, cut);
}

}  // namespace bearing_calibration

const char* SeedMethodName(BearingSeedMethod method) {
  switch (method) {
    case BearingSeedMethod::kClosedForm:
      return "closed_form";
    case BearingSeedMethod::kSearch:
      return "search";
    case BearingSeedMethod::kNone:
      return "";
  }
  return "";
}

StatusOr<BearingCalibrationResult> CalibrateBearing(const BearingLog& log,
                                                    const BearingCalibrationOptions& options) {
  CALIB_RETURN_IF_ERROR(ValidateBearingLog(log));
  const std::string source = log.source.empty() ? "bearing log" : log.source;
  CALIB_RETURN_IF_ERROR(CheckEnoughBearings(log).Prefixed(source + ": "));
  const Progress progress = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  if (options.bearing_sigma_rad && !(*options.bearing_sigma_rad > 0.0)) {
    return Status::InvalidInput("the bearing noise σβ must be positive");
  }
  if (options.encoder_noise_k && !(*options.encoder_noise_k >= 0.0)) {
    return Status::InvalidInput("the encoder noise K must be non-negative");
  }
  BearingCalibrationResult result;
  result.loss = LossStagesName(options.adjustment.loss, options.adjustment.redescending_scale);
  auto clock = std::chrono::steady_clock::now();

  // Bearings that disagree with their neighbours in time are left out of the seeds; the
  // adjustment keeps them under its robust loss. The neighbours' agreement also gives the scale
  // of σβ whatever the seed.
  const BearingConsistency consistency = CheckConsistency(log);
  result.bearing_scatter_rad = consistency.sigma_rad;
  const BearingMask keep =
      SeedSelection(log, consistency, options.seed_outlier_cut, &result.seed_excluded);
  const BearingNoise noise = InitialNoise(options, consistency.sigma_rad, &result);
  CALIB_ASSIGN_OR_RETURN(SeedChoice seed, ChooseSeed(log, keep, noise, consistency.sigma_rad,
                                                     options, progress, source, &result));
  BearingProblem& problem = *seed.problem;
  if (log.meta.initial_distance) {
    result.has_seed_metric = true;
    result.seed_metric =
        result.seed_method == BearingSeedMethod::kClosedForm && result.closed_form.has_metric
            ? result.closed_form.metric
            : BearingMetricFromScaled(result.seed, seed.landmarks[InitialDistanceRun(log)].norm(),
                                      log.meta.initial_distance->meters, log.meta.wheelbase_m);
  }
  result.seed_seconds = Seconds(clock);
  clock = std::chrono::steady_clock::now();

  StatusOr<BearingMask> inlier =
      bearing_calibration::EstimateNoise(options, progress, &problem, &seed.summary, &result);
  if (!inlier.ok()) return inlier.status().Prefixed(source + ": ");
  // The timing model: τ and the stamp jitter, each kept only when the data ask for it (the
  // problem is then replaced by the one that models them).
  CALIB_RETURN_IF_ERROR(bearing_calibration::ApplyTimingModel(log, options, progress, &seed.problem,
                                                              &seed.summary, &*inlier, &result)
                            .Prefixed(source + ": "));
  BearingProblem& final_problem = *seed.problem;
  result.converged = Converged(seed.summary);
  if (!result.converged) {
    result.warnings.push_back(NotConvergedText("the bundle adjustment", seed.summary));
  }
  result.noise = final_problem.noise();
  result.estimate = final_problem.params();
  result.poses = final_problem.poses();
  for (const BearingRunNodes& nodes : final_problem.nodes()) {
    result.node_times_s.push_back(nodes.t_s);
  }
  result.residuals_rad = final_problem.BearingErrors();
  result.adjustment_seconds = Seconds(clock);
  clock = std::chrono::steady_clock::now();

  CALIB_RETURN_IF_ERROR(
      ComputeCovariance(log, options, &final_problem, &result).Prefixed(source + ": "));
  CALIB_RETURN_IF_ERROR(
      bearing_calibration::FinishTiming(&final_problem, &result).Prefixed(source + ": "));
  result.covariance_seconds = Seconds(clock);
  if (const Status determined = CheckDetermined(options, &result); !determined.ok()) {
    // Swapped wheel columns can leave a log that looks undetermined.
    if (!options.check_readings) return determined.Prefixed(source + ": ");
    return SwappedOr(log, options, determined.message(), result.noise.bearing_sigma_rad,
                     determined.Prefixed(source + ": "));
  }
  SummarizeRuns(log, final_problem, *inlier, &result);
  JudgeOutliers(&result);
  result.is_inlier = *inlier;
  if (options.timing.sensor_clock) {
    CALIB_ASSIGN_OR_RETURN(
        result, bearing_calibration::TrySensorClock(log, options, progress, final_problem, *inlier,
                                                    std::move(result)));
  }
  bearing_calibration::AddStreamTimingWarnings(log, &result);
  if (options.check_readings) CALIB_RETURN_IF_ERROR(CheckBearingReadings(log, options, result));
  return result;
}

}  // namespace calib
