#include <calib/core/laser/laser_simulator.h>
#include <calib/core/laser/robot_integrator.h>
#include <calib/core/laser/wheel_profile.h>
#include <calib/core/random.h>
#include <calib/core/timing/logging_model.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <utility>

// How the simulator works
//
// The wheel speeds are a piecewise analytic profile (wheel_profile.h), so the cumulative encoder
// angles are known in closed form at any time. The robot's motion, with the effects of
// LaserEffects, is integrated from that profile per scan window without storing the path
// (robot_integrator.cc). This file draws the timing and the outliers and writes the two outputs.
//
// Randomness comes from independent streams per purpose (timing, targets, scan noise, outliers,
// wheel noise, pose noise), so that e.g. a noisy log and a noise-free log with the same seed show
// exactly the same motion, and turning an effect on changes the motion only by that effect.
namespace calib {
namespace {

enum Stream : uint32_t {
  kTiming = 1,
  kTargets,
  kScanNoise,
  kOutliers,
  kWheelNoise,
  kPoseNoise,
  kLoggerTiming,  // The logging model's draws.
  kEncoderTiming,
  kRepeats,
  kChainedScanNoise = 9001,  // The value calib_bench's timing section drew from before.
};

using laser_sim_internal::ConstantSpeedProfile;
using laser_sim_internal::IntegrateRobotMotions;
using laser_sim_internal::SmoothProfile;
using laser_sim_internal::WheelProfile;

// Everything both outputs share: the timing, the wheel profile, the true robot motion per scan
// window and the scan matcher's noise-free answer (outliers included).
struct Simulation {
  std::vector<double> boundaries;  // t_0 … t_N on the odometry clock.
  WheelProfile profile{0.0, {}};
  std::vector<Pose2d> matched;  // Per interval: sm before noise (the outlier's, if one).
  std::vector<bool> is_outlier;
};

std::vector<double> Boundaries(const LaserSimOptions& options) {
  Random random(options.seed, Stream::kTiming);
  const int n = std::max(options.num_intervals, 0);
  // A jitter of at most half the mean keeps every interval positive.
  const double jitter =
      std::min(std::abs(options.interval_jitter_s), 0.5 * options.mean_interval_s);
  std::vector<double> boundaries(n + 1, 0.0);
  for (int k = 0; k < n; ++k) {
    boundaries[k + 1] = boundaries[k] + options.mean_interval_s + random.Uniform(-jitter, jitter);
  }
  return boundaries;
}

// Slip outliers: round(fraction·N) intervals chosen at random. Half (all, without scan noise) are
// a wheel slip: the robot moved only a random fraction in [0, 0.5] of its displacement; the others,
// and slips too small to stand out of the noise (under outlier_scale/2 sigmas in every component:
// such a slip is a model effect, not an outlier), are a gross match error of
// ±outlier_scale·σ·U(0.5, 1.5) per component.
void AddOutliers(const LaserSimOptions& options, const std::vector<Pose2d>& robot_motions,
                 Simulation* simulation) {
  const size_t n = simulation->matched.size();
  simulation->is_outlier.assign(n, false);
  const double fraction = std::clamp(options.outlier_fraction, 0.0, 1.0);
  const size_t count = std::min(n, static_cast<size_t>(std::llround(fraction * n)));
  if (count == 0) return;
  Random random(options.seed, Stream::kOutliers);
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  const Eigen::Vector3d& sigma = options.scan_noise_sigma;
  const bool has_noise = sigma.cwiseAbs().maxCoeff() > 0.0;
  for (size_t i = 0; i < count; ++i) {
    std::swap(order[i], order[i + random.Index(n - i)]);  // Partial Fisher–Yates.
    const size_t k = order[i];
    simulation->is_outlier[k] = true;
    const bool slip = !has_noise || random.Uniform() < 0.5;
    const Pose2d slipped_match = SensorMotionFromRobotMotion(
        options.base_T_sensor, Pose2d(random.Uniform(0.0, 0.5) * robot_motions[k]));
    const Eigen::Vector3d slip_error = slipped_match - simulation->matched[k];
    const bool gross_slip = !has_noise || (slip_error.cwiseAbs().array() >
                                           0.5 * options.outlier_scale * sigma.cwiseAbs().array())
                                              .any();
    if (slip && gross_slip) {
      simulation->matched[k] = slipped_match;
    } else {
      for (int j = 0; j < 3; ++j) {
        simulation->matched[k](j) +=
            random.Sign() * random.Uniform(0.5, 1.5) * options.outlier_scale * std::abs(sigma(j));
      }
    }
  }
}

// The motion seen by scans taken at `boundaries` (t_0 … t_N); the wheel profile runs at least
// until `end_s`, so that samples after the last scan can be read from it.
Simulation SimulateAt(const LaserSimOptions& options, std::vector<double> boundaries, double end_s,
                      LaserSimTruth* truth) {
  Simulation simulation;
  if (boundaries.size() >= 2) {
    simulation.boundaries = std::move(boundaries);
    end_s = std::max(end_s,
                     simulation.boundaries.back() + std::max(options.effects.time_offset_s, 0.0));
    Random targets(options.seed, Stream::kTargets);
    simulation.profile = options.speed_time_constant_s > 0.0
                             ? SmoothProfile(options, end_s, &targets)
                             : ConstantSpeedProfile(options, simulation.boundaries, &targets);
    const std::vector<Pose2d> robot_motions =
        IntegrateRobotMotions(options, simulation.profile, simulation.boundaries);
    simulation.matched.reserve(robot_motions.size());
    for (const Pose2d& motion : robot_motions) {
      simulation.matched.push_back(SensorMotionFromRobotMotion(options.base_T_sensor, motion));
    }
    AddOutliers(options, robot_motions, &simulation);
  }
  if (truth != nullptr) {
    truth->odometry = options.odometry;
    truth->base_T_sensor = options.base_T_sensor;
    truth->effects = options.effects;
    truth->is_outlier = simulation.is_outlier;
  }
  return simulation;
}

Simulation Simulate(const LaserSimOptions& options, LaserSimTruth* truth) {
  std::vector<double> boundaries;
  if (options.num_intervals > 0 && options.mean_interval_s > 0.0) boundaries = Boundaries(options);
  return SimulateAt(options, std::move(boundaries), 0.0, truth);
}

// The scan matcher's world poses of the sensor at t_0 … t_N: chained from the noise-free
// displacements (so an outlier corrupts only its own displacement), then each with independent
// noise N(0, σ/√2) composed in the sensor frame. A displacement between consecutive poses thus
// has noise of about σ per component, as in the log, but consecutive displacements share a pose
// and are correlated (about −1/2).
std::vector<Pose2d> MeasuredSensorPoses(const LaserSimOptions& options,
                                        const Simulation& simulation) {
  const size_t n = simulation.matched.size();
  Random pose_noise(options.seed, Stream::kPoseNoise);
  const Eigen::Vector3d sigma = options.scan_noise_sigma / std::sqrt(2.0);
  std::vector<Pose2d> poses;
  poses.reserve(n + 1);
  Pose2d sensor = options.base_T_sensor;  // The robot starts at the world origin.
  for (size_t k = 0; k <= n; ++k) {
    Pose2d noise;
    for (int j = 0; j < 3; ++j) noise(j) = sigma(j) * pose_noise.Normal();
    Pose2d measured = Compose(sensor, noise);
    measured(2) = WrapAngle(measured(2));
    poses.push_back(measured);
    if (k < n) {
      sensor = Compose(sensor, simulation.matched[k]);
      sensor(2) = WrapAngle(sensor(2));
    }
  }
  return poses;
}

// Encoder reading: the count of whole ticks when quantized.
Eigen::Array2d Quantize(const Eigen::Array2d& angle, double ticks_per_rad) {
  if (ticks_per_rad <= 0.0) return angle;
  return (angle * ticks_per_rad).floor() / ticks_per_rad;
}

}  // namespace

LaserLog SimulateLaserLog(const LaserSimOptions& options, LaserSimTruth* truth) {
  const Simulation simulation = Simulate(options, truth);
  LaserLog log;
  log.source = "simulation";
  log.has_timestamps = true;
  const size_t n = simulation.matched.size();
  if (n == 0) return log;
  log.intervals.resize(n);
  Random scan_noise(options.seed, Stream::kScanNoise);
  Random wheel_noise(options.seed, Stream::kWheelNoise);
  const double ticks = options.encoder_ticks_per_rad;
  const int steps = std::max(options.record_steps, 0);
  size_t cursor = 0;
  Eigen::Array2d angle_start = Quantize(simulation.profile.Angle(0.0, &cursor), ticks);
  for (size_t k = 0; k < n; ++k) {
    LaserInterval& interval = log.intervals[k];
    const double start = simulation.boundaries[k];
    const double end = simulation.boundaries[k + 1];
    interval.start_s = start;
    interval.duration_s = end - start;
    interval.record = static_cast<int>(k + 1);
    const Eigen::Array2d angle_end = Quantize(simulation.profile.Angle(end, &cursor), ticks);
    // White noise on the reported mean speeds; the steps share it evenly so they still sum to φ·T.
    Eigen::Array2d noise = Eigen::Array2d::Zero();
    if (options.wheel_speed_noise > 0.0) {
      noise << options.wheel_speed_noise * wheel_noise.Normal(),
          options.wheel_speed_noise * wheel_noise.Normal();
    }
    const Eigen::Array2d speed = (angle_end - angle_start) / interval.duration_s + noise;
    interval.left_speed = speed(0);
    interval.right_speed = speed(1);
    if (steps > 0) {
      interval.steps.resize(steps);
      size_t step_cursor = cursor;
      Eigen::Array2d previous = angle_start;
      for (int j = 0; j < steps; ++j) {
        const Eigen::Array2d current =
            j + 1 == steps
                ? angle_end
                : Quantize(simulation.profile.Angle(start + interval.duration_s * (j + 1) / steps,
                                                    &step_cursor),
                           ticks);
        WheelStep& step = interval.steps[j];
        step.duration_s = interval.duration_s / steps;
        step.left_rad = current(0) - previous(0) + noise(0) * step.duration_s;
        step.right_rad = current(1) - previous(1) + noise(1) * step.duration_s;
        previous = current;
      }
    }
    Pose2d sm = simulation.matched[k];
    for (int j = 0; j < 3; ++j) sm(j) += options.scan_noise_sigma(j) * scan_noise.Normal();
    if (std::abs(sm(2)) > M_PI) sm(2) = WrapAngle(sm(2));
    interval.sensor_motion = sm;
    angle_start = angle_end;
  }
  return log;
}

// Sensor poses as MeasuredSensorPoses makes them. Encoder samples are quantized like the log's but
// carry no wheel-speed noise; with encoder_rate_hz <= 0 they are taken at the interval boundaries.
LaserStreams SimulateLaserStreams(const LaserSimOptions& options, double encoder_rate_hz,
                                  LaserSimTruth* truth) {
  const Simulation simulation = Simulate(options, truth);
  LaserStreams streams;
  const size_t n = simulation.matched.size();
  if (n == 0) return streams;
  const double ticks = options.encoder_ticks_per_rad;
  size_t cursor = 0;
  const auto sample = [&](double t) {
    const Eigen::Array2d angle = Quantize(simulation.profile.Angle(t, &cursor), ticks);
    return EncoderSample{t, angle(0), angle(1)};
  };
  if (encoder_rate_hz > 0.0) {
    const double end = simulation.boundaries.back();
    size_t count = static_cast<size_t>(std::ceil(end * encoder_rate_hz - 1e-9)) + 1;
    // The last sample at or after the last scan (the boundaries are sums that can overshoot a
    // whole number of encoder periods by a few ulps).
    if (static_cast<double>(count - 1) / encoder_rate_hz < end) ++count;
    streams.odometry.reserve(count);
    for (size_t j = 0; j < count; ++j) {
      streams.odometry.push_back(sample(static_cast<double>(j) / encoder_rate_hz));
    }
  } else {
    streams.odometry.reserve(n + 1);
    for (const double t : simulation.boundaries) streams.odometry.push_back(sample(t));
  }

  const std::vector<Pose2d> poses = MeasuredSensorPoses(options, simulation);
  streams.sensor_poses.reserve(n + 1);
  for (size_t k = 0; k <= n; ++k) {
    streams.sensor_poses.push_back(StampedPose{simulation.boundaries[k], poses[k]});
  }
  return streams;
}

// The logging model on top of the same machinery: the scans are the sensor's true samples (its own
// grid when it free-runs), the logger decides which sample each row holds and its stamp, and the
// encoders are read from the wheel profile at the true poll times.
LaserStreams SimulateLoggedLaserStreams(const LaserSimOptions& options, const LoggingModel& model,
                                        LaserSimTruth* truth, LoggedTimingTruth* timing) {
  std::vector<double> samples;
  if (options.num_intervals > 0 && model.sensor_period_s > 0.0) {
    samples = FreeRunningSampleTimes(model, static_cast<size_t>(options.num_intervals) + 1);
  } else if (options.num_intervals > 0 && options.mean_interval_s > 0.0) {
    samples = Boundaries(options);
  }
  Random logger(options.seed, Stream::kLoggerTiming);
  Random encoder(options.seed, Stream::kEncoderTiming);
  Random repeats(options.seed, Stream::kRepeats);
  const std::vector<LoggedSample> records = LogSamples(model, samples, &logger);
  double end_s = samples.empty() ? 0.0 : samples.back();
  for (const LoggedSample& record : records) end_s = std::max(end_s, record.stamp_s);
  const std::vector<EncoderPoll> polls = model.encoder_period_s > 0.0 && !samples.empty()
                                             ? EncoderPolls(model, samples.front(), end_s, &encoder)
                                             : StampedPolls(model, samples, &encoder);
  for (const EncoderPoll& poll : polls) end_s = std::max(end_s, poll.true_s);
  const Simulation simulation = SimulateAt(options, samples, end_s, truth);

  LaserStreams streams;
  LoggedTimingTruth timing_truth;
  timing_truth.all_sensor_sample_times_s = samples;
  if (!simulation.matched.empty()) {
    const std::vector<Pose2d> poses = MeasuredSensorPoses(options, simulation);
    std::vector<bool> written(samples.size(), false);
    size_t previous = 0;
    for (const size_t row : RowsWithRepeats(records.size(), model.repeat_fraction, &repeats)) {
      const LoggedSample& record = records[row];
      const bool duplicate = !streams.sensor_poses.empty() && row == previous;
      timing_truth.sensor_duplicates += duplicate;
      timing_truth.held_samples += !duplicate && written[record.sample];
      written[record.sample] = true;
      previous = row;
      streams.sensor_poses.push_back(StampedPose{record.stamp_s, poses[record.sample]});
      timing_truth.sensor_sample_time_s.push_back(samples[record.sample]);
      timing_truth.sensor_sample_index.push_back(record.sample);
    }
    timing_truth.skipped_samples = std::count(written.begin(), written.end(), false);
    const double ticks = options.encoder_ticks_per_rad;
    size_t cursor = 0;
    previous = 0;
    for (const size_t row : RowsWithRepeats(polls.size(), model.repeat_fraction, &repeats)) {
      const EncoderPoll& poll = polls[row];
      timing_truth.encoder_duplicates += !streams.odometry.empty() && row == previous;
      previous = row;
      const Eigen::Array2d angle = Quantize(simulation.profile.Angle(poll.true_s, &cursor), ticks);
      streams.odometry.push_back(EncoderSample{poll.stamp_s, angle(0), angle(1)});
      timing_truth.encoder_sample_time_s.push_back(poll.true_s);
    }
  }
  if (timing != nullptr) *timing = std::move(timing_truth);
  return streams;
}

std::vector<LaserInterval> DropBackwardIntervals(const std::vector<LaserInterval>& intervals,
                                                 const OdometryParams& odometry) {
  std::vector<LaserInterval> kept;
  bool dropped = false;
  for (const LaserInterval& interval : intervals) {
    const double v = odometry.left_radius_m * interval.left_speed +
                     odometry.right_radius_m * interval.right_speed;
    if (v < -1e-9) {
      dropped = true;
      continue;
    }
    kept.push_back(interval);
    kept.back().gap_before = dropped && kept.size() > 1;
    dropped = false;
  }
  return kept;
}

void ChainScanMatcherNoise(const Eigen::Vector3d& sigma, const std::vector<size_t>& sample_index,
                           uint64_t seed, std::vector<StampedPose>* poses) {
  if (poses->empty()) return;
  Random random(seed, Stream::kChainedScanNoise);
  Pose2d previous_true = poses->front().world_T_sensor;
  for (size_t k = 1; k < poses->size(); ++k) {
    Pose2d& pose = (*poses)[k].world_T_sensor;
    const Pose2d true_pose = pose;
    if (!sample_index.empty() && sample_index[k] == sample_index[k - 1]) {
      pose = (*poses)[k - 1].world_T_sensor;
      continue;
    }
    Pose2d noise;
    for (int j = 0; j < 3; ++j) noise(j) = sigma(j) * random.Normal();
    pose = Compose((*poses)[k - 1].world_T_sensor,
                   Compose(Compose(Inverse(previous_true), true_pose), noise));
    pose(2) = WrapAngle(pose(2));
    previous_true = true_pose;
  }
}

}  // namespace calib
