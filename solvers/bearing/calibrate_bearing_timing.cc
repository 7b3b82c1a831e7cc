// The timing model of CalibrateBearing: the clock offset τ and the stamp jitter σ_t, each
// tested on the plain fit and modelled when significant (solvers/bearing/bearing_timing.h).
#include <calib/solvers/bearing/bearing_text.h>
#include <calib/solvers/bearing/calibrate_bearing_internal.h>
#include <calib/solvers/stats/score_test.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace calib::bearing_calibration {
namespace {

constexpr int kJitterRounds = 4;
constexpr double kJitterTolerance = 0.03;

// τ freed from the plain fit: the likelihood-ratio test (2·Δ(½Σρ)/s ~ χ²₁, s the loss's scale)
// and σ of τ. When significant, `*problem` becomes the fit with τ, its noise re-estimated.
Status TestTimeOffset(const BearingLog& log, const BearingCalibrationOptions& options,
                      const Progress& progress, std::unique_ptr<BearingProblem>* problem,
                      ceres::Solver::Summary* summary, BearingMask* inlier,
                      BearingCalibrationResult* result) {
  BearingTiming& timing = result->timing;
  const BearingProblem& plain = **problem;
  const BearingProblem::LossConstants loss = plain.BearingLossConstants();
  BearingAdjustmentOptions adjustment = options.adjustment;
  adjustment.model_time_offset = true;
  adjustment.time_offset_s = 0.0;
  adjustment.fix_time_offset = false;
  auto with_offset = std::make_unique<BearingProblem>(log, plain.params(), plain.poses(),
                                                      plain.noise(), adjustment);
  ceres::Solver::Summary with_summary;
  if (!with_offset->Solve(&with_summary).ok()) {
    progress("time offset: the fit with τ did not converge; stamps kept as sample times");
    return Status::Ok();
  }
  timing.time_offset_tested = true;
  timing.time_offset_free_s = with_offset->time_offset();
  timing.time_offset_lr =
      std::max(0.0, 2.0 * (plain.Cost() - with_offset->Cost()) / loss.likelihood_ratio_scale);
  timing.time_offset_p_value = ChiSquareSurvival(timing.time_offset_lr, 1);
  const StatusOr<BearingProblem::TimeOffsetCovariance> cov =
      with_offset->CovarianceWithTimeOffset();
  if (!cov.ok()) {
    // τ is not separable from the poses (e.g. constant-speed circles): nothing to model.
    timing.time_offset_p_value = 1.0;
    return Status::Ok();
  }
  timing.time_offset_stddev_s =
      std::sqrt(std::max(0.0, cov->joint(kNumBearingParams, kNumBearingParams)) *
                with_offset->LossCorrection());
  progress("time offset: " + Num(timing.time_offset_free_s * 1e3, 3) + " ± " +
           Num(timing.time_offset_stddev_s * 1e3, 2) + " ms, LR " + Num(timing.time_offset_lr, 3) +
           ", p = " + Num(timing.time_offset_p_value, 2));
  if (!(timing.time_offset_p_value <= options.timing.significance) &&
      !options.timing.keep_time_offset) {
    return Status::Ok();
  }
  timing.time_offset_modelled = true;
  *problem = std::move(with_offset);
  *summary = with_summary;
  result->iterations += static_cast<int>(with_summary.iterations.size());
  CALIB_ASSIGN_OR_RETURN(*inlier,
                         EstimateNoise(options, progress, problem->get(), summary, result));
  timing.time_offset_s = (*problem)->time_offset();
  return Status::Ok();
}

// The inlier bearings' errors and rates (BearingTerms' order), flagged by the cut on each
// bearing's own σ; `inlier` is updated.
BearingJitterEstimate JitterAtFit(const BearingProblem& problem, double cut, double fraction,
                                  double significance, BearingMask* inlier) {
  const std::vector<std::vector<double>> errors = problem.BearingErrors();
  const std::vector<double> rates = problem.BearingRates();
  const std::vector<double> sigmas = problem.BearingSigmas();
  const std::vector<BearingProblem::BearingTermInfo> terms = problem.BearingTerms();
  std::vector<double> e, g;
  for (size_t t = 0; t < terms.size(); ++t) {
    const double error = errors[terms[t].run][terms[t].bearing];
    const bool in = std::abs(error) <= cut * sigmas[t];
    (*inlier)[terms[t].run][terms[t].bearing] = in;
    if (!in) continue;
    e.push_back(error);
    g.push_back(rates[t]);
  }
  return EstimateBearingJitter(e, g, fraction, significance);
}

// σ_t on the current fit; when significant, each bearing whitened by √(σβ² + σ_t²·rate²) and the
// fit re-solved, σβ and σ_t re-estimated until they settle (K kept).
Status TestJitter(const BearingCalibrationOptions& options, const Progress& progress,
                  BearingProblem* problem, ceres::Solver::Summary* summary, BearingMask* inlier,
                  BearingCalibrationResult* result) {
  BearingTiming& timing = result->timing;
  const double cut = std::sqrt(options.inlier_chi2);
  int inliers = 0;
  for (const auto& run : *inlier)
    inliers += static_cast<int>(std::count(run.begin(), run.end(), true));
  // The residuals' shrinkage by their leverage, as the variance components saw it.
  const double fraction =
      inliers > 0 && result->bearing_redundancy > 0.0 ? result->bearing_redundancy / inliers : 1.0;
  BearingMask flags = *inlier;
  timing.jitter = JitterAtFit(*problem, cut, fraction, options.timing.significance, &flags);
  timing.jitter_tested = true;
  progress("stamp jitter: " + Num(timing.jitter.jitter_s * 1e3, 3) + " ± " +
           Num(timing.jitter.jitter_stddev_s * 1e3, 2) + " ms, LR " +
           Num(timing.jitter.lr_statistic, 3) + ", p = " + Num(timing.jitter.p_value, 2));
  if (!timing.jitter.significant) return Status::Ok();
  timing.jitter_modelled = true;
  const BearingJitterEstimate test = timing.jitter;
  for (int round = 0; round < kJitterRounds; ++round) {
    BearingNoise noise = problem->noise();
    const double change =
        std::max(std::abs(timing.jitter.jitter_s / std::max(noise.bearing_jitter_s, 1e-12) - 1.0),
                 std::abs(timing.jitter.bearing_sigma_rad / noise.bearing_sigma_rad - 1.0));
    if (round > 0 && change < kJitterTolerance) break;
    noise.bearing_sigma_rad = timing.jitter.bearing_sigma_rad;
    noise.bearing_jitter_s = timing.jitter.jitter_s;
    problem->SetNoise(noise);
    problem->Relinearize();
    CALIB_RETURN_IF_ERROR(problem->Solve(summary));
    result->iterations += static_cast<int>(summary->iterations.size());
    flags = *inlier;
    timing.jitter = JitterAtFit(*problem, cut, fraction, options.timing.significance, &flags);
  }
  // The test is that of the plain fit; the values those of the final one.
  timing.jitter.lr_statistic = test.lr_statistic;
  timing.jitter.p_value = test.p_value;
  timing.jitter.significant = true;
  *inlier = flags;
  return Status::Ok();
}

}  // namespace

Status ApplyTimingModel(const BearingLog& log, const BearingCalibrationOptions& options,
                        const Progress& progress, std::unique_ptr<BearingProblem>* problem,
                        ceres::Solver::Summary* summary, BearingMask* inlier,
                        BearingCalibrationResult* result) {
  result->timing.plain_bearing_sigma_rad = (*problem)->noise().bearing_sigma_rad;
  if (options.timing.time_offset) {
    CALIB_RETURN_IF_ERROR(TestTimeOffset(log, options, progress, problem, summary, inlier, result));
  }
  if (options.timing.stamp_jitter) {
    CALIB_RETURN_IF_ERROR(TestJitter(options, progress, problem->get(), summary, inlier, result));
  }
  result->timing.treatment = BearingTimingTreatment(result->timing);
  result->timing.statement = BearingTimingStatement(result->timing);
  return Status::Ok();
}

void AddStreamTimingWarnings(const BearingLog& log, BearingCalibrationResult* result) {
  const BearingTiming& timing = result->timing;
  const BearingClockEstimate& clock = timing.clock;
  if (clock.free_running && !timing.clock_modelled) {
    const std::string shown = std::to_string(clock.held_samples) + " samples picked up twice, " +
                              std::to_string(clock.skipped_samples) + " missed";
    result->warnings.push_back(
        clock.period_determined
            ? "the bearings come from a free-running sensor picked up by the logger (" + shown +
                  ") but the calibration re-fitted on its clock did not explain them as well; "
                  "the timing may bias the calibration"
            : "the bearings come from a free-running sensor picked up by the logger (" + shown +
                  ") whose period the log cannot fix: its stamps step by " +
                  Num(clock.stamp_step_s * 1e3, 6) +
                  " ms, and a sensor period off that by a fraction ε scales the time, hence the "
                  "turn rate ξ, by ε (samples the logger missed do not show in its stamps); the "
                  "calibration may be biased by that much beyond its sigmas");
  }
  for (const StreamTiming& stream : log.stream_timing) {
    if (stream.stamps_are_sample_times) continue;
    // The clock model is what those stamps need; the statement says so.
    if (timing.clock_modelled && stream.stream == "bearings") continue;
    std::string why;
    if (stream.free_running_signature) {
      AppendReason(&why, "they show a free-running sensor picked up by the logger");
    }
    if (stream.jitter_s > 0.0) {
      AppendReason(&why, "they scatter by " + Num(stream.jitter_s * 1e3, 3) + " ms about a " +
                             Num(stream.period_s * 1e3, 4) + " ms grid");
    }
    for (const std::string& note : stream.notes) AppendReason(&why, note);
    const std::string source = stream.source.empty() ? stream.stream : stream.source;
    result->warnings.push_back(
        source + ": the " + stream.stream + " stamps cannot be the sample times (" + why +
        "); the calibration models only a clock offset and a white stamp jitter of the bearings "
        "against the encoders (" +
        result->timing.treatment + "), so its sigmas may be too small");
  }
}

Status FinishTiming(BearingProblem* problem, BearingCalibrationResult* result) {
  BearingTiming& timing = result->timing;
  if (timing.time_offset_modelled) {
    CALIB_ASSIGN_OR_RETURN(const BearingProblem::TimeOffsetCovariance cov,
                           problem->CovarianceWithTimeOffset());
    timing.time_offset_stddev_s = std::sqrt(
        std::max(0.0, cov.joint(kNumBearingParams, kNumBearingParams)) * result->covariance_scale);
    timing.statement = BearingTimingStatement(timing);
  }
  return Status::Ok();
}

}  // namespace calib::bearing_calibration
