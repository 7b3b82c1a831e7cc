#include <calib/solvers/common/solver_options.h>
#include <calib/solvers/timing/timing_model_fit.h>

#include <algorithm>
#include <cmath>

namespace calib {
namespace {

// Jitter σ's are searched in [kJitterFloor, period]: below 0.1 ms no log can tell them from 0.
constexpr double kJitterFloor = 1e-4;

// Pick-up stamps lag their sample by [c, c + P) with c the logger's fixed delay (≥ 0 up to its
// jitter): c is estimated as a low quantile of the lags, and each index is the sample whose time
// lies in that window before its stamp.
std::vector<double> ReassignClockIndices(const StreamSamples& data, const LatentTimeState& s) {
  std::vector<double> lags, stamps;
  for (size_t k = 0; k < data.samples.size(); ++k) {
    stamps.push_back(data.samples[k].stamp_s);
    lags.push_back(stamps.back() - s.clock.Time(s.clock_index[k]));
  }
  std::vector<double> sorted = lags;
  const size_t q = sorted.size() / 50;
  std::nth_element(sorted.begin(), sorted.begin() + q, sorted.end());
  SampleClock shifted = s.clock;
  shifted.t0_s += sorted[q] - 0.02 * s.clock.period_s;
  return ClockIndicesFromStamps(stamps, shifted);
}

double RelativeChange(double now, double before) {
  return std::abs(now - before) / std::max(std::abs(now), 1e-12);
}

// Score = 2·cost + log det(H_ll + Λ) + Σ log σ_i² + N·log|Σ_scan| + 2·globals.
double Score(const TimingModelFit& fit, double final_cost, const LatentPrior& prior) {
  const double n = static_cast<double>(fit.errors.size());
  const int timing_globals = fit.model == SensorClockModel::kFreeRunning ? 3 : 1;
  return 2.0 * final_cost + fit.covariance.log_det + 2.0 * prior.sigma.array().log().sum() +
         n * 2.0 * fit.state.noise_sigma.array().log().sum() + 2.0 * (timing_globals + 1);
}

}  // namespace

LatentTimeState ClockStartFromTimes(const StreamSamples& data, const LatentTimeState& stamps,
                                    const std::vector<double>& sample_time_s) {
  LatentTimeState s = stamps;
  const double period = MedianStep(sample_time_s);
  s.clock_index = ClockIndicesFromTimes(sample_time_s, period);
  s.clock = FitSampleClock(s.clock_index, sample_time_s);
  s.clock_index = ReassignClockIndices(data, s);
  s.clock = FitSampleClock(s.clock_index, sample_time_s);
  s.bracket.clear();
  return s;
}

StatusOr<TimingModelFit> FitTimingModel(const StreamSamples& data, SensorClockModel model,
                                        const LatentTimeState& initial,
                                        const LaserTimingOptions& options) {
  TimingModelFit fit;
  fit.model = model;
  fit.state = initial;
  const bool fit_sensor = model == SensorClockModel::kStamps && !options.sensor_jitter_s;
  const bool fit_encoder = !options.encoder_jitter_s;
  const double ceiling = std::max(data.sensor_period_s, data.encoder_period_s);
  for (int round = 0; round < std::max(1, options.max_rounds); ++round) {
    LatentTimeProblem problem(data, model, fit.state, options.calibration.refinement,
                              options.estimate_offset);
    ceres::Solver::Summary summary;
    CALIB_RETURN_IF_ERROR(problem.Solve(&summary));
    fit.iterations += static_cast<int>(summary.iterations.size());
    fit.converged = Converged(summary);
    fit.rounds = round + 1;
    fit.state = problem.state();
    fit.errors = problem.Errors();
    CALIB_ASSIGN_OR_RETURN(fit.lin, problem.Linearize());
    const LatentPrior prior = MakeLatentPrior(fit.lin, fit.state.offset_s, fit.state.sensor_sigma_s,
                                              fit.state.encoder_sigma_s);
    CALIB_ASSIGN_OR_RETURN(fit.covariance, MarginalLatentCovariance(fit.lin, prior));
    fit.sample_time_s.clear();
    for (size_t k = 0; k < data.samples.size(); ++k) {
      fit.sample_time_s.push_back(problem.SampleTime(static_cast<int>(k)));
    }
    fit.score = Score(fit, summary.final_cost, prior);

    // Scan noise: robust level of the errors, inflated for the share of the fit that the latents
    // and globals took (they absorb part of the noise).
    const double components = 3.0 * fit.errors.size();
    const double redundancy = components - fit.lin.num_globals - fit.covariance.effective_latents;
    const Eigen::Vector3d noise =
        options.calibration.noise_sigma
            ? *options.calibration.noise_sigma
            : RobustNoiseSigma(fit.errors) * std::sqrt(components / std::max(redundancy, 1.0));
    JitterScales jitter{fit.state.sensor_sigma_s, fit.state.encoder_sigma_s};
    if (fit_sensor || fit_encoder) {
      jitter = MaximizeLatentEvidence(fit.lin, fit.state.offset_s, jitter, fit_sensor, fit_encoder,
                                      kJitterFloor, std::max(ceiling, 2 * kJitterFloor));
    }
    bool settled =
        problem.BracketsHold() &&
        ((noise - fit.state.noise_sigma).cwiseQuotient(noise)).cwiseAbs().maxCoeff() < 0.01 &&
        RelativeChange(jitter.sensor_s, fit.state.sensor_sigma_s) < 0.05 &&
        RelativeChange(jitter.encoder_s, fit.state.encoder_sigma_s) < 0.05;
    if (model == SensorClockModel::kFreeRunning) {
      const std::vector<double> indices = ReassignClockIndices(data, fit.state);
      if (indices != fit.state.clock_index) {
        settled = false;
        fit.state.clock_index = indices;
      }
    }
    if (settled) break;
    if (!problem.BracketsHold()) fit.state.bracket = problem.Brackets();
    fit.state.noise_sigma = noise;
    fit.state.sensor_sigma_s = jitter.sensor_s;
    fit.state.encoder_sigma_s = jitter.encoder_s;
  }
  const double components = 3.0 * fit.errors.size();
  const double redundancy = components - fit.lin.num_globals - fit.covariance.effective_latents;
  if (!(redundancy > 0.0)) return Status::NotObservable("too few intervals for the timing model");
  CALIB_ASSIGN_OR_RETURN(fit.kappa, LossCorrection(fit.lin.loss_sums, components, redundancy));
  return fit;
}

}  // namespace calib
