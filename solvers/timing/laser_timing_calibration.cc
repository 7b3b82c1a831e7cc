#include <calib/core/timing/stamp_timing.h>
#include <calib/core/timing/stream_samples.h>
#include <calib/solvers/laser/laser_consistency.h>
#include <calib/solvers/laser/laser_dead_reckoning.h>
#include <calib/solvers/timing/clock_start.h>
#include <calib/solvers/timing/laser_timing_calibration.h>
#include <calib/solvers/timing/pick_up_clock.h>
#include <calib/solvers/timing/timing_model_fit.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <string>

namespace calib {
namespace {

// Neighbouring stamp intervals correlated below this: scatter about a grid (−0.5 for white
// scatter), not an irregular sampler's independent intervals (0).
constexpr double kScatterAboutAGrid = -0.2;

// A free-running sensor stamped at pick-up is worth trying where records repeat (held samples) or
// the stream shows the free-running signature (steps at constant speed off their usual whole
// multiple), or where the stamps keep to a grid within a tenth of the period (the logger's own
// period) and are either regular or scattered about it (neighbouring intervals anti-correlated);
// the evidence then decides. An irregular sampler's stamps (independent intervals) are its sample
// times, with no clock behind them: on the simulator's default 2000-interval logs at 0.5 rad/s the
// evidence could not tell and chose a clock whose stamps sat ±130 ms off it.
bool ClockCandidate(const StreamSamples& data) {
  if (data.samples.size() < 50) return false;
  if (data.held_repeats_dropped > 0) return true;
  std::vector<double> stamps, values, deviation;
  for (const StreamSample& s : data.samples) {
    stamps.push_back(s.stamp_s);
    values.insert(values.end(), s.world_T_sensor.data(), s.world_T_sensor.data() + 3);
  }
  const StreamTiming timing = AnalyzeStreamTiming(stamps, values);
  if (timing.free_running_signature) return true;
  for (size_t k = 1; k < stamps.size(); ++k) {
    deviation.push_back(std::abs(stamps[k] - stamps[k - 1] - data.sensor_period_s));
  }
  std::nth_element(deviation.begin(), deviation.begin() + deviation.size() / 2, deviation.end());
  const bool on_grid = 1.4826 * deviation[deviation.size() / 2] < 0.1 * data.sensor_period_s;
  return on_grid && (timing.regular || timing.interval_correlation < kScatterAboutAGrid);
}

// The six parameters' covariance in the ambient space, times κ.
LaserParamMatrix ParameterCovariance(const TimingModelFit& fit) {
  Eigen::Matrix<double, 6, 6> plus = Eigen::Matrix<double, 6, 6>::Identity();
  plus.topLeftCorner<3, 3>() = fit.lin.odometry_plus_jacobian;
  return plus * fit.globals_covariance.topLeftCorner<6, 6>() * plus.transpose();
}

// The free-running clock model is adopted in auto mode only within this many σ of the stamp
// model (its scores can favour it with a few misassigned sample indices).
constexpr double kClockAgreement = 2.0;
// Scores (−2 log evidence) closer than this are compared only after both models are polished: the
// rounds stop at a cost gain of kLatentRoundCostTolerance per interval, well inside it on the logs
// tried.
constexpr double kPolishBothMargin = 50.0;

// The largest change of the six parameters between two fits, in σ of both combined.
double ParameterShift(const TimingModelFit& a, const TimingModelFit& b) {
  const LaserParamVector difference =
      a.state.calibration.ToVector() - b.state.calibration.ToVector();
  const LaserParamVector variance = (ParameterCovariance(a) + ParameterCovariance(b)).diagonal();
  return difference.cwiseQuotient(variance.cwiseMax(1e-300).cwiseSqrt()).cwiseAbs().maxCoeff();
}

std::string FormatDouble(double value, int digits) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.*f", digits, value);
  return text;
}

// The distinct streams (held repeats and duplicates dropped) on their original clock.
LaserStreams DistinctStreams(const StreamSamples& data) {
  LaserStreams streams;
  for (EncoderSample s : data.encoders) {
    s.t_s += data.origin_s;
    streams.odometry.push_back(s);
  }
  for (const StreamSample& s : data.samples) {
    streams.sensor_poses.push_back(
        StampedPose{s.stamp_s + data.origin_s, s.world_T_sensor, s.line, s.segment});
  }
  return streams;
}

// The distinct streams with every sample at its estimated time (encoders at stamp + η_j).
LaserStreams TimedStreams(const StreamSamples& data, const TimingModelFit& fit) {
  LaserStreams streams = DistinctStreams(data);
  for (size_t j = 0; j < streams.odometry.size() && j < fit.state.encoder_latent.size(); ++j) {
    streams.odometry[j].t_s += fit.state.encoder_latent[j];
  }
  for (size_t k = 0; k < streams.sensor_poses.size(); ++k) {
    streams.sensor_poses[k].t_s = fit.sample_time_s[k] + data.origin_s;
  }
  const auto by_time = [](const auto& a, const auto& b) { return a.t_s < b.t_s; };
  std::stable_sort(streams.odometry.begin(), streams.odometry.end(), by_time);
  std::stable_sort(streams.sensor_poses.begin(), streams.sensor_poses.end(), by_time);
  return streams;
}

bool Redescends(const LaserTimingOptions& options) {
  const LaserRefinementOptions& refinement = options.calibration.refinement;
  return refinement.loss != RobustLoss::kNone && refinement.redescending_scale > 0.0;
}

// The chosen model's last passes under Tukey's biweight from its (Cauchy) optimum, as the
// refinement on stamps ends: a gross interval then has no influence, where Cauchy leaks a fixed
// bias that a σ shrinking as 1/√N stops covering. The models were ranked under one loss before.
// The Cauchy fit's statistics are computed only where it stays (the passes failed).
Status Redescend(const StreamSamples& data, const LaserTimingOptions& options, TimingModelFit* best,
                 std::string* loss, std::vector<std::string>* warnings) {
  const LaserRefinementOptions& refinement = options.calibration.refinement;
  *loss = RobustLossName(refinement.loss);
  if (!Redescends(options)) return Status::Ok();
  LaserTimingOptions tukey = options;
  tukey.calibration.refinement.loss = RobustLoss::kTukey;
  tukey.calibration.refinement.loss_scale = refinement.redescending_scale;
  // What the polish starts from: it recomputes the rest (a whole copy held the linearisation and
  // the covariance twice at the run's peak of memory).
  TimingModelFit redescended;
  redescended.model = best->model;
  redescended.state = best->state;
  redescended.iterations = best->iterations;
  redescended.rounds = best->rounds;
  const Status polished = PolishTimingModel(data, tukey, &redescended);
  if (!polished.ok()) {
    warnings->push_back("the timing-aware refinement's last passes under Tukey's loss failed (" +
                        polished.message() + "): it ends under " + *loss);
    return best->has_statistics ? Status::Ok() : PolishTimingModel(data, options, best);
  }
  *best = std::move(redescended);
  *loss = LossStagesName(refinement.loss, refinement.redescending_scale);
  return Status::Ok();
}

void FillCalibration(const TimingModelFit& fit, const LaserCalibrationOptions& options,
                     LaserCalibrationResult* out) {
  out->estimate = fit.state.calibration;
  out->covariance = ParameterCovariance(fit);
  out->stddev = out->covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  out->covariance_scale = fit.kappa;
  out->samples = static_cast<int>(fit.errors.size());
  out->iterations = fit.iterations;
  out->converged = fit.converged;
  out->inliers = 0;
  std::vector<bool> inlier;
  const Eigen::Vector3d inverse_sigma = fit.state.noise_sigma.cwiseInverse();
  for (const Eigen::Vector3d& e : fit.errors) {
    inlier.push_back(e.cwiseProduct(inverse_sigma).squaredNorm() < options.inlier_chi2);
    out->inliers += inlier.back();
  }
  out->is_inlier = {inlier};
  out->noise_sigma = {fit.state.noise_sigma};
  out->warnings.clear();
  out->observability = AnalyzeLaserObservability(out->covariance, out->estimate, out->census);
}

// The timing-free totals (laser_consistency.h) at the timing-aware estimate, over the intervals
// between the samples' estimated times with that estimate's inliers. A total telescopes only
// across the intervals it counts: on the stamps' intervals the samples that a logger slower than
// its sensor skipped were the stamp-as-truth fit's outliers, and leaving them out read as a 7σ
// rotation mismatch where the estimate was within 1σ. The timing enters at the window ends only,
// as on the stamps.
LaserConsistency TimingFreeTotals(const LaserLog& stamped, const LaserCalibrationOptions& options,
                                  const LaserTimingResult& result) {
  const LaserCalibrationResult& c = result.calibration;
  const StatusOr<LaserLog> timed = LaserLogFromStreams(
      result.timed_streams.odometry, result.timed_streams.sensor_poses, "streams");
  if (!timed.ok()) {
    return CheckLaserConsistency(stamped.intervals, c.estimate, c.covariance,
                                 result.stamps_as_truth.noise_sigma.front(),
                                 result.stamps_as_truth.is_inlier.front());
  }
  const Eigen::Vector3d& sigma = c.noise_sigma.front();
  return CheckLaserConsistency(
      timed->intervals, c.estimate, c.covariance, sigma,
      ClassifyLaserInliers(LaserIntervalErrors(timed->intervals, c.estimate), sigma,
                           options.inlier_chi2));
}

// τ, the period and the per-sample times with their σ.
void FillTiming(const StreamSamples& data, const TimingModelFit& fit, LaserTimingResult* out) {
  const Eigen::MatrixXd& cov = fit.globals_covariance;  // κ included.
  const int n = static_cast<int>(data.samples.size());
  out->sample_time_s.assign(n, 0.0);
  out->sample_time_stddev_s.assign(n, 0.0);
  out->sample_record.assign(n, 0);
  out->sample_line.assign(n, 0);
  Eigen::VectorXd latent_sd = Eigen::VectorXd::Zero(n);
  for (Eigen::Index i = 0; i < fit.lin.latent_value.size(); ++i) {
    if (fit.lin.latent_is_sensor[i]) {
      latent_sd(fit.lin.latent_owner[i]) =
          std::sqrt(std::max(0.0, fit.kappa * fit.covariance.latent_variance(i)));
    }
  }
  Eigen::Vector3d mean_gradient = Eigen::Vector3d::Zero();  // d mean(t − s)/d(t0, P, a).
  double mean_lag = 0.0;
  for (int k = 0; k < n; ++k) {
    out->sample_time_s[k] = fit.sample_time_s[k] + data.origin_s;
    out->sample_record[k] = data.samples[k].record;
    out->sample_line[k] = data.samples[k].line;
    mean_lag += (fit.sample_time_s[k] - data.samples[k].stamp_s) / n;
    if (fit.model == SensorClockModel::kFreeRunning) {
      const double index = fit.state.clock_index[k];
      const Eigen::Vector3d g(1.0, index, fit.state.clock.Curvature(index));
      mean_gradient += g / n;
      out->sample_time_stddev_s[k] = std::sqrt(std::max(0.0, g.dot(cov.block<3, 3>(6, 6) * g)));
    } else {
      out->sample_time_stddev_s[k] = latent_sd(k);
    }
  }
  if (fit.model == SensorClockModel::kFreeRunning) {
    out->sensor_clock = "free_running";
    out->time_offset_s = mean_lag;
    out->time_offset_stddev_s =
        std::sqrt(std::max(0.0, mean_gradient.dot(cov.block<3, 3>(6, 6) * mean_gradient)));
    out->sensor_jitter_s = fit.state.sensor_sigma_s;  // The stamps' scatter about the clock.
    out->sensor_period_s = fit.state.clock.period_s;
    out->sensor_period_stddev_s = std::sqrt(std::max(0.0, cov(7, 7)));
    out->clock_drift_s = fit.state.clock.drift_s;
  } else {
    out->sensor_clock = "stamps";
    out->time_offset_s = fit.state.offset_s;
    if (fit.lin.offset_global >= 0) {
      const int i = fit.lin.offset_global;
      out->time_offset_stddev_s = std::sqrt(std::max(0.0, cov(i, i)));
    }
    out->sensor_period_s = data.sensor_period_s;
    out->sensor_jitter_s = fit.state.sensor_sigma_s;
  }
  out->encoder_jitter_s = fit.state.encoder_sigma_s;
  out->neighbour_correlation = fit.neighbours.correlation.diagonal();
  out->pose_errors = fit.neighbours.PoseErrors();
}

}  // namespace

StatusOr<LaserTimingResult> CalibrateLaserStreams(const LaserStreams& streams,
                                                  const LaserTimingOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (options.sensor_clock != "auto" && options.sensor_clock != "stamps" &&
      options.sensor_clock != "free_running") {
    return Status::InvalidInput("sensor clock '" + options.sensor_clock +
                                "': expected auto, stamps or free_running");
  }
  CALIB_ASSIGN_OR_RETURN(const StreamSamples data,
                         BuildStreamSamples(streams.odometry, streams.sensor_poses, "streams"));
  LaserTimingResult result;
  result.held_repeats_dropped = data.held_repeats_dropped;
  result.intervals = static_cast<int>(data.interval_start.size());
  // A stream that stops a sample later than the other is how recordings end: a sample or two
  // within two periods of the span is counted in the JSON (samples_outside_encoder_span) only.
  const double edge_s = 2.0 * std::max(data.sensor_period_s, data.encoder_period_s);
  result.outside_encoder_span = data.outside_encoder_span;
  if (data.outside_encoder_span > 2 || data.outside_by_s > edge_s) {
    result.warnings.push_back(std::to_string(data.outside_encoder_span) + " of " +
                              std::to_string(streams.sensor_poses.size()) +
                              " sensor samples lie outside the encoders' time span and are not "
                              "used: do the two streams share a clock and cover the same run?");
  }
  bool try_clock = options.sensor_clock == "free_running" ||
                   (options.sensor_clock == "auto" && ClockCandidate(data));
  // Held repeats under distinct stamps that a pick-up clock names every sample from: the stamps
  // are pick-up times, not sample times, and in auto mode the stamp model is not fitted (it took
  // most of the time on such logs); the clock starts from the stamp-as-truth fit. The clock's
  // search needs only the stamps: it runs beside the stamp-as-truth calibration.
  std::future<std::optional<PickUpClock>> pick_up_search;
  if (options.sensor_clock == "auto" && try_clock && data.held_repeats_dropped > 0) {
    pick_up_search = std::async(std::launch::async, [&data] { return FitPickUpClock(data); });
  }
  const LaserStreams distinct = DistinctStreams(data);
  CALIB_ASSIGN_OR_RETURN(const LaserLog log,
                         LaserLogFromStreams(distinct.odometry, distinct.sensor_poses, "streams"));
  LaserCalibrationOptions stamps_options = options.calibration;
  stamps_options.interval_jitter = false;  // The seed and the comparison: stamps as sample times.
  // The latent-time fit keeps its own (Cauchy) loss; its seed comes from the same loss.
  stamps_options.refinement.redescending_scale = 0.0;
  CALIB_ASSIGN_OR_RETURN(result.stamps_as_truth, CalibrateLaser(log.intervals, stamps_options));

  LatentTimeState initial;
  initial.calibration = result.stamps_as_truth.estimate;
  initial.noise_sigma = result.stamps_as_truth.noise_sigma.front();
  std::vector<double> sensor_stamps, encoder_stamps;
  for (const StreamSample& s : data.samples) sensor_stamps.push_back(s.stamp_s);
  for (const EncoderSample& e : data.encoders) encoder_stamps.push_back(e.t_s);
  initial.sensor_sigma_s =
      options.sensor_jitter_s.value_or(StartingJitter(sensor_stamps, data.sensor_period_s));
  initial.encoder_sigma_s =
      options.encoder_jitter_s.value_or(StartingJitter(encoder_stamps, data.encoder_period_s));
  std::optional<PickUpClock> pick_up;
  if (pick_up_search.valid()) pick_up = pick_up_search.get();
  // Stamps that count the sensor's periods (a grid the motion confirms) name every sample too:
  // the clock model then starts from the stamp-as-truth fit (the stamp model's rounds had taken
  // most of the time on such logs, and the clock model won by far on every one tried).
  const bool named =
      (pick_up && pick_up->NamesEverySample()) ||
      (try_clock && options.sensor_clock == "auto" && StampsCountSensorPeriods(data, initial));
  const bool try_stamps = options.sensor_clock != "free_running" && !named;
  // Otherwise the stamp model runs first: its latent times seed the clock model.
  TimingModelFit best;
  best.state = initial;
  if (!named) {
    CALIB_ASSIGN_OR_RETURN(best, FitTimingModel(data, SensorClockModel::kStamps, initial, options));
    result.stamps_score = best.score;
    result.rounds = best.rounds;
  }
  std::optional<LatentTimeState> clock_start;
  if (try_clock) {
    if (!pick_up && !named) pick_up = MotionCountedPickUpClock(data, initial);
    clock_start = ClockStartFromTimes(data, best, pick_up);
    // Sample times that stray from every grid rule a clock out, unless holds or counted skips
    // named its samples (a logger whose own steps wander still picks up a clock's samples).
    if (try_stamps && !clock_start->clock_indices_named && TimesStrayFromEveryClock(data, best)) {
      try_clock = false;
    }
  }
  if (try_clock) {
    StatusOr<TimingModelFit> clock =
        FitTimingModel(data, SensorClockModel::kFreeRunning, *clock_start, options);
    // The rounds' looser optimum ranks the two models unless their scores are close; then both
    // are polished first.
    if (clock.ok() && try_stamps && std::abs(clock->score - best.score) < kPolishBothMargin) {
      CALIB_RETURN_IF_ERROR(PolishTimingModel(data, options, &best));
      result.stamps_score = best.score;
      const Status polished = PolishTimingModel(data, options, &*clock);
      if (!polished.ok()) clock = polished;
    }
    if (clock.ok()) {
      result.free_running_score = clock->score;
      result.rounds += clock->rounds;
      // Where the motion inferred the clock's sample indices, a wrong one shifts every later
      // time: in auto mode the clock model must then also agree with the stamp model's six
      // parameters. Indices named by pick-up stamps are exact.
      if (!try_stamps) {
        best = std::move(clock).value();
      } else if (const double shift = ParameterShift(best, *clock);
                 clock->score < best.score && shift > kClockAgreement &&
                 !clock->state.clock_indices_named) {
        result.warnings.push_back(
            "the free-running clock model fits better but moves a parameter by " +
            FormatDouble(shift, 1) +
            " σ from the stamp model: its inferred sample indices are likely wrong somewhere, "
            "so the stamp model is used");
      } else if (clock->score < best.score) {
        best = std::move(clock).value();
      }
    } else if (named) {
      result.warnings.push_back("the free-running clock model failed (" + clock.message() +
                                ") although the stamps name every sample: the stamp model is "
                                "used");
      CALIB_ASSIGN_OR_RETURN(best,
                             FitTimingModel(data, SensorClockModel::kStamps, initial, options));
    } else if (!try_stamps) {
      return clock.status();
    } else {
      result.warnings.push_back("the free-running clock model failed (" + clock.message() +
                                "): the stamp model is used");
    }
  }
  if (!best.polished) {
    CALIB_RETURN_IF_ERROR(PolishTimingModel(data, options, &best, !Redescends(options)));
  }
  if (best.model == SensorClockModel::kStamps) {
    result.stamps_score = best.score;
  } else {
    result.free_running_score = best.score;
  }
  // Stamps on the clock's grid (a stamp prior within 5 % of the period) name every sample.
  const bool indices_from_stamps = best.state.sensor_sigma_s > 0.0 &&
                                   best.state.sensor_sigma_s < 0.05 * best.state.clock.period_s;
  if (best.model == SensorClockModel::kFreeRunning && !indices_from_stamps &&
      !best.state.clock_indices_named) {
    result.warnings.push_back(
        "the free-running sensor's sample indices are inferred from the motion and the stamps: "
        "across stretches where the robot stood still a sample time may be whole periods off, "
        "which the sample times' σ does not include (the calibration is not affected)");
  }
  result.calibration = result.stamps_as_truth;
  CALIB_RETURN_IF_ERROR(
      Redescend(data, options, &best, &result.calibration.loss, &result.warnings));
  FillCalibration(best, options.calibration, &result.calibration);
  FillTiming(data, best, &result);
  result.timed_streams = TimedStreams(data, best);
  if (!best.converged) {
    result.warnings.push_back("the timing-aware refinement stopped before converging");
  }
  result.calibration.consistency = TimingFreeTotals(log, options.calibration, result);
  result.warnings.insert(result.warnings.end(), result.calibration.consistency.warnings.begin(),
                         result.calibration.consistency.warnings.end());
  result.calibration.warnings = result.warnings;
  result.calibration.observability.warnings.insert(result.calibration.observability.warnings.end(),
                                                   result.warnings.begin(), result.warnings.end());
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace calib
