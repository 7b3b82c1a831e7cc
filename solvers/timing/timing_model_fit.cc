#include <calib/core/timing/encoder_integration.h>
#include <calib/core/timing/stamp_timing.h>
#include <calib/solvers/common/robust_covariance.h>
#include <calib/solvers/common/solver_options.h>
#include <calib/solvers/timing/clock_indices.h>
#include <calib/solvers/timing/latent_error_covariance.h>
#include <calib/solvers/timing/pick_up_clock.h>
#include <calib/solvers/timing/timing_model_fit.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>

namespace calib {
namespace {

double RelativeChange(double now, double before) {
  return std::abs(now - before) / std::max(std::abs(now), 1e-12);
}

NoiseScales ScalesOf(const LatentTimeState& s) {
  return NoiseScales{s.noise_sigma, s.sensor_sigma_s, s.encoder_sigma_s};
}

// The σ's have settled: scan noise within 3 %, jitters within 10 %.
bool ScalesSettled(const NoiseScales& before, const NoiseScales& now) {
  return ((now.scan - before.scan).cwiseQuotient(now.scan)).cwiseAbs().maxCoeff() < 0.03 &&
         RelativeChange(now.sensor_s, before.sensor_s) < 0.1 &&
         RelativeChange(now.encoder_s, before.encoder_s) < 0.1;
}

// Or the evidence gains less than this (−2 log) from them: a σ the log hardly determines (a
// jitter near the floor) moves by tens of % between rounds without changing the fit.
constexpr double kSettledEvidenceGain = 1.0;

// Aitken's extrapolation of the σ update, per σ in log: from x0 → x1 = F(x0) → x2 = F(x1) with
// steps shrinking by q = Δ2/Δ1 ∈ (0, 0.75], the fixed point x2 + Δ2·q/(1 − q). The rounds'
// update converges linearly: the stamps-as-truth scan noise, inflated by the timing, takes four or
// five rounds to shed (re-solving the globals inside the evidence was tried and changed little).
double ExtrapolateLog(double x0, double x1, double x2) {
  if (!(x0 > 0.0 && x1 > 0.0 && x2 > 0.0)) return x2;
  const double d1 = std::log(x1 / x0), d2 = std::log(x2 / x1);
  if (!(d1 * d2 > 0.0) || std::abs(d2) >= std::abs(d1)) return x2;
  const double q = std::min(d2 / d1, 0.75);
  return x2 * std::exp(d2 * q / (1.0 - q));
}

NoiseScales ExtrapolateScales(const NoiseScales& x0, const NoiseScales& x1, const NoiseScales& x2,
                              const NoiseScaleFit& what) {
  NoiseScales out = x2;
  if (what.scan) {
    for (int c = 0; c < 3; ++c) out.scan(c) = ExtrapolateLog(x0.scan(c), x1.scan(c), x2.scan(c));
  }
  const auto jitter = [&](double a, double b, double c) {
    return std::clamp(ExtrapolateLog(a, b, c), what.floor_s, what.ceiling_s);
  };
  if (what.sensor) out.sensor_s = jitter(x0.sensor_s, x1.sensor_s, x2.sensor_s);
  if (what.encoder) out.encoder_s = jitter(x0.encoder_s, x1.encoder_s, x2.encoder_s);
  return out;
}

// The Bartlett lag of the sandwich's scores, in intervals: the wheel angles between two polls
// come from a cubic whose rates use the neighbouring polls, so an error of it spans three polls.
int ScoreLag(const StreamSamples& data) {
  if (!(data.sensor_period_s > 0.0)) return 1;
  return std::clamp(static_cast<int>(std::ceil(3.0 * data.encoder_period_s / data.sensor_period_s)),
                    1, 50);
}

// −2 log evidence (Laplace, latents integrated out) + 2·(timing globals + 1).
double Score(const TimingModelFit& fit, const NoiseScales& scales) {
  const int timing_globals = fit.model == SensorClockModel::kFreeRunning ? 3 : 1;
  const StatusOr<double> evidence = LatentNegLogEvidence(fit.lin, fit.state.offset_s, scales);
  double value = (evidence.ok() ? *evidence : INFINITY) + 2.0 * (timing_globals + 1);
  if (fit.lin.stamp_prior_count > 0) {  // The clock model's stamps, at σ_s = scales.sensor_s.
    const double ratio = fit.state.sensor_sigma_s / scales.sensor_s;
    value += fit.lin.stamp_prior_chi2 * ratio * ratio +
             2.0 * fit.lin.stamp_prior_count * std::log(scales.sensor_s);
  }
  return value;
}

// The fit's state, errors and statistics at the problem's current point (σ's as they were).
Status CaptureFit(const StreamSamples& data, const LatentTimeProblem& problem, TimingModelFit* fit,
                  bool with_scores = false) {
  fit->state = problem.state();
  fit->errors = problem.Errors();
  CALIB_ASSIGN_OR_RETURN(fit->lin, problem.Linearize(with_scores));
  const LatentPrior prior = MakeLatentPrior(fit->lin, fit->state.offset_s,
                                            fit->state.sensor_sigma_s, fit->state.encoder_sigma_s);
  CALIB_ASSIGN_OR_RETURN(fit->covariance, MarginalLatentCovariance(fit->lin, prior));
  fit->globals_covariance = fit->kappa * fit->covariance.globals;
  fit->sample_time_s.clear();
  for (size_t k = 0; k < data.samples.size(); ++k) {
    fit->sample_time_s.push_back(problem.SampleTime(static_cast<int>(k)));
  }
  fit->score = Score(*fit, NoiseScales{fit->state.noise_sigma, fit->state.sensor_sigma_s,
                                       fit->state.encoder_sigma_s});
  return Status::Ok();
}

// The globals' covariance as reported (TimingModelFit::globals_covariance): the model's, κ·C, at
// least the sandwich's in every direction (the sandwich keeps structure in the errors that the
// model leaves out). With scan poses that err independently the intervals' errors are correlated
// (−1/2 between neighbours) and κ·C overstates the low frequencies several times over, so the
// model's gets the lag-1 term, floored at 1 % of κ·C in every direction. Those directions' variance
// goes as 1 + 2R, and R is estimated (−0.43 where −0.47 would be exact on the simulator's logs;
// −0.5 made the σ's 1.7 times too small): the sandwich bounds it from below.
Status ReportCovariance(const StreamSamples& data, double components, double redundancy,
                        TimingModelFit* fit) {
  Eigen::MatrixXd model = fit->kappa * fit->covariance.globals;
  fit->neighbours =
      NeighbourErrorCorrelation(fit->errors, fit->state.noise_sigma, data.interval_start);
  if (fit->neighbours.PoseErrors()) {
    CALIB_ASSIGN_OR_RETURN(
        const Eigen::MatrixXd shared,
        LatentNeighbourCovariance(fit->lin, fit->covariance, fit->neighbours.correlation));
    // The floor goes first: it is factored, and the lag-1 model may be indefinite where R errs.
    model = DominatingCovariance(0.01 * model, model + fit->kappa * shared).covariance;
  }
  const LatentPrior prior = MakeLatentPrior(fit->lin, fit->state.offset_s,
                                            fit->state.sensor_sigma_s, fit->state.encoder_sigma_s);
  const StatusOr<Eigen::MatrixXd> sandwich = LatentSandwichCovariance(
      fit->lin, prior, fit->covariance, ScoreLag(data), components, redundancy);
  const DominatingCovarianceResult reported =
      DominatingCovariance(model, sandwich.ok() ? *sandwich : model);
  fit->sandwich_ratio = reported.largest_ratio;
  CALIB_ASSIGN_OR_RETURN(const Eigen::MatrixXd angles,
                         LatentAngleCovariance(fit->lin, fit->covariance));
  fit->globals_covariance = reported.covariance + angles;
  return Status::Ok();
}

}  // namespace

double StartingJitter(const std::vector<double>& stamps_s, double period_s) {
  const StreamTiming timing = AnalyzeStreamTiming(stamps_s);
  // Steps that vary and add up (an irregular sampler) scatter about a grid without being jitter:
  // only the white part, which anti-correlates neighbouring steps, is.
  const double white = std::min(timing.jitter_s, timing.pickup_scatter_s);
  return std::clamp(2.0 * white, kJitterFloor, std::max(kJitterFloor, 0.25 * period_s));
}

StatusOr<TimingModelFit> FitTimingModel(const StreamSamples& data, SensorClockModel model,
                                        const LatentTimeState& initial,
                                        const LaserTimingOptions& options) {
  TimingModelFit fit;
  fit.model = model;
  fit.state = initial;
  NoiseScaleFit what;
  what.scan = !options.calibration.noise_sigma;
  what.sensor = model == SensorClockModel::kStamps && !options.sensor_jitter_s;
  what.encoder = !options.encoder_jitter_s;
  what.floor_s = kJitterFloor;
  what.ceiling_s = std::max({data.sensor_period_s, data.encoder_period_s, 2 * kJitterFloor});
  what.num_threads = options.calibration.refinement.num_threads;
  std::vector<NoiseScales> entered;  // The σ's each round was solved with.
  // Rebuilt only when the brackets or the clock's indices change; new σ's are set in place.
  std::unique_ptr<LatentTimeProblem> problem;
  for (int round = 0; round < std::max(1, options.max_rounds); ++round) {
    if (!problem) {
      problem = std::make_unique<LatentTimeProblem>(
          data, model, fit.state, options.calibration.refinement, options.estimate_offset);
    } else {
      CALIB_RETURN_IF_ERROR(problem->SetNoiseScales(fit.state.noise_sigma, fit.state.sensor_sigma_s,
                                                    fit.state.encoder_sigma_s));
    }
    // The rounds only re-estimate the σ's, which a looser optimum serves as well.
    BandArrowSummary summary;
    CALIB_RETURN_IF_ERROR(problem->Solve(&summary, kLatentRoundCostTolerance,
                                         kLatentRoundGlobalStep, kLatentRoundMaxIterations));
    fit.iterations += summary.iterations;
    fit.rounds = round + 1;
    CALIB_RETURN_IF_ERROR(CaptureFit(data, *problem, &fit));
    const NoiseScales current = ScalesOf(fit.state);
    entered.push_back(current);
    // Scan noise and jitters together, by the evidence with the latents integrated out.
    double gain = 0.0;
    NoiseScales next = MaximizeLatentEvidence(fit.lin, fit.state.offset_s, current, what, &gain);
    if (model == SensorClockModel::kFreeRunning && fit.lin.stamp_prior_count > 4 &&
        !options.sensor_jitter_s) {
      // The clock's pick-up scatter: the RMS of t − s − τ (four clock and offset parameters).
      const double rms = fit.state.sensor_sigma_s *
                         std::sqrt(fit.lin.stamp_prior_chi2 / (fit.lin.stamp_prior_count - 4));
      next.sensor_s = std::clamp(rms, kJitterFloor, what.ceiling_s);
    }
    bool settled = ScalesSettled(current, next) || gain < kSettledEvidenceGain;
    if (!problem->BracketsHold()) {
      fit.state.bracket = problem->Brackets();
      problem.reset();
    }
    if (model == SensorClockModel::kFreeRunning && !fit.state.clock_indices_named) {
      const std::vector<double> indices = ReassignClockIndices(data, fit.state);
      if (indices != fit.state.clock_index) {
        settled = false;
        fit.state.clock_index = indices;
        problem.reset();
      }
    }
    if (settled) break;
    // Every other round, the σ's jump towards the fixed point the last two rounds head for.
    if (entered.size() % 2 == 0) next = ExtrapolateScales(entered.end()[-2], current, next, what);
    fit.state.noise_sigma = next.scan;
    fit.state.sensor_sigma_s = next.sensor_s;
    fit.state.encoder_sigma_s = next.encoder_s;
  }
  return fit;
}

Status PolishTimingModel(const StreamSamples& data, const LaserTimingOptions& options,
                         TimingModelFit* fit, bool with_statistics) {
  LatentTimeProblem problem(data, fit->model, fit->state, options.calibration.refinement,
                            options.estimate_offset);
  BandArrowSummary summary;
  CALIB_RETURN_IF_ERROR(problem.Solve(&summary, kLatentCostTolerance, kLatentGlobalStep));
  fit->iterations += summary.iterations;
  fit->converged = summary.converged;
  fit->polished = true;
  fit->has_statistics = with_statistics;
  CALIB_RETURN_IF_ERROR(CaptureFit(data, problem, fit, /*with_scores=*/with_statistics));
  if (!with_statistics) return Status::Ok();
  const double components = 3.0 * fit->errors.size();
  const double redundancy = components - fit->lin.num_globals - fit->covariance.effective_latents;
  if (!(redundancy > 0.0)) return Status::NotObservable("too few intervals for the timing model");
  CALIB_ASSIGN_OR_RETURN(fit->kappa, LossCorrection(fit->lin.loss_sums, components, redundancy));
  CALIB_RETURN_IF_ERROR(ReportCovariance(data, components, redundancy, fit));
  fit->lin.score_globals.resize(0, 0);
  fit->lin.score_latents.clear();
  for (Eigen::MatrixXd& a : fit->lin.angle_globals) a.resize(0, 0);
  for (Eigen::MatrixXd& a : fit->lin.row_globals) a.resize(0, 0);
  return Status::Ok();
}

}  // namespace calib
