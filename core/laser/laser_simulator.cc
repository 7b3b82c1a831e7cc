#include <calib/core/laser/laser_simulator.h>
#include <calib/core/laser/robot_integrator.h>
#include <calib/core/laser/wheel_profile.h>
#include <calib/core/random.h>

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

Simulation Simulate(const LaserSimOptions& options, LaserSimTruth* truth) {
  Simulation simulation;
  if (options.num_intervals > 0 && options.mean_interval_s > 0.0) {
    simulation.boundaries = Boundaries(options);
    const double end_s =
        simulation.boundaries.back() + std::max(options.effects.time_offset_s, 0.0);
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

// Sensor poses are chained from the noise-free scan-matcher displacements (so an outlier corrupts
// only its own displacement), then each gets independent noise N(0, σ/√2) composed in the sensor
// frame. A displacement between consecutive poses thus has noise of about σ per component, as in
// the log, but consecutive displacements share a pose and are correlated (about −1/2).
// Encoder samples are quantized like the log's but carry no wheel-speed noise; with
// encoder_rate_hz <= 0 they are taken at the interval boundaries.
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
    const size_t count = static_cast<size_t>(std::ceil(end * encoder_rate_hz - 1e-9)) + 1;
    streams.odometry.reserve(count);
    for (size_t j = 0; j < count; ++j) {
      streams.odometry.push_back(sample(static_cast<double>(j) / encoder_rate_hz));
    }
  } else {
    streams.odometry.reserve(n + 1);
    for (const double t : simulation.boundaries) streams.odometry.push_back(sample(t));
  }

  Random pose_noise(options.seed, Stream::kPoseNoise);
  const Eigen::Vector3d sigma = options.scan_noise_sigma / std::sqrt(2.0);
  streams.sensor_poses.reserve(n + 1);
  Pose2d sensor = options.base_T_sensor;  // The robot starts at the world origin.
  for (size_t k = 0; k <= n; ++k) {
    Pose2d noise;
    for (int j = 0; j < 3; ++j) noise(j) = sigma(j) * pose_noise.Normal();
    Pose2d measured = Compose(sensor, noise);
    measured(2) = WrapAngle(measured(2));
    streams.sensor_poses.push_back(StampedPose{simulation.boundaries[k], measured});
    if (k < n) {
      sensor = Compose(sensor, simulation.matched[k]);
      sensor(2) = WrapAngle(sensor(2));
    }
  }
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

}  // namespace calib
