#include <calib/core/laser/laser_simulator.h>
#include <calib/core/random.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <numeric>
#include <random>
#include <utility>

// How the simulator works
//
// Wheel speeds are a piecewise analytic profile: segments of constant commanded targets g, and
// within a segment either constant speeds (speed_time_constant_s == 0; segments then start only
// at interval boundaries) or a first-order lag φ(t) = g + (φ_a − g)·exp(−(t − a)/τ). The
// cumulative encoder angles Φ(t) are therefore known in closed form at any time.
//
// The robot's heading is closed form too, θ(t) = θ_a + (r_r·ΔΦ_r − r_l·ΔΦ_l)/b (the slip effects
// do not turn the robot), so the position is a plain quadrature of R(θ(t))·(u, w) with
// u = v − γ_long·dv/dt and w = γ_lat·v·ω. Where the speeds are constant the body twist is
// constant and the motion is the exact SE(2) exponential. Where they vary, 4-point
// Gauss–Legendre panels are used; every discontinuity (new target, radius change, scan time) is a
// panel end, so the integrand is analytic on each panel. Its derivatives scale like 1/τ^k and
// ω^k, hence panels of half the shortest of τ and 1/ω have errors near 1e-14 m (the step model's
// error falls as (T/steps)² down to 5e-12 m at 3200 steps). integration_step_s is only a lower
// bound on the panel length: the default 0.002 s never binds, a larger value coarsens the sum.
// Work per interval is thus a few panels, whatever the step, and no path is stored.
//
// With constant speeds, a speed change at a boundary is a jump of v, and the longitudinal slip
// u = v − γ·dv/dt integrates to an impulse: a forward displacement of −γ·Δv at that instant. A
// scan taken exactly at the boundary (time_offset_s = 0) sees half of it, as if the speed changed
// along a short ramp centred on the boundary; so interval k moves by −γ·(v_{k+1} − v_{k−1})/2.
// A radius change is a change of the wheels, not an acceleration: it causes no impulse.
//
// Randomness comes from independent streams per purpose (timing, targets, scan noise, outliers,
// wheel noise, pose noise), so that e.g. a noisy log and a noise-free log with the same seed show
// exactly the same motion, and turning an effect on changes the motion only by that effect.
namespace calib {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

enum Stream : uint32_t {
  kTiming = 1,
  kTargets,
  kScanNoise,
  kOutliers,
  kWheelNoise,
  kPoseNoise,
};

// One commanded target, held from start_s until the next segment starts; the first segment also
// covers all earlier times (at constant speed, since the profile starts at its target).
struct SpeedSegment {
  double start_s = 0.0;
  Eigen::Array2d target = Eigen::Array2d::Zero();  // (left, right), rad/s.
  Eigen::Array2d speed = Eigen::Array2d::Zero();   // Actual speeds at start_s.
  Eigen::Array2d angle = Eigen::Array2d::Zero();   // Cumulative wheel angles at start_s.
};

class WheelProfile {
 public:
  WheelProfile(double time_constant_s, std::vector<SpeedSegment> segments)
      : tau_(time_constant_s), segments_(std::move(segments)) {}

  bool smooth() const { return tau_ > 0.0; }
  double tau() const { return tau_; }
  const std::vector<SpeedSegment>& segments() const { return segments_; }

  // The segment holding t; `cursor` remembers the last answer, since queries mostly move forward.
  size_t Find(double t, size_t* cursor) const {
    size_t i = std::min(*cursor, segments_.size() - 1);
    while (i + 1 < segments_.size() && segments_[i + 1].start_s <= t) ++i;
    while (i > 0 && segments_[i].start_s > t) --i;
    return *cursor = i;
  }

  // Φ(a + dt) − Φ(a) = g·dt + (φ_a − g)·τ·(1 − exp(−dt/τ)). Only the first segment is evaluated
  // at dt < 0, where φ_a = g; the clamp keeps 0·exp(large) from becoming 0·inf.
  Eigen::Array2d Rotation(const SpeedSegment& segment, double dt) const {
    if (!smooth()) return segment.target * dt;
    return segment.target * dt +
           (segment.speed - segment.target) * (-tau_ * std::expm1(-std::max(dt, 0.0) / tau_));
  }
  Eigen::Array2d Speed(const SpeedSegment& segment, double dt) const {
    if (!smooth()) return segment.target;
    return segment.target + (segment.speed - segment.target) * std::exp(-std::max(dt, 0.0) / tau_);
  }

  // Cumulative wheel angles Φ(t).
  Eigen::Array2d Angle(double t, size_t* cursor) const {
    const SpeedSegment& segment = segments_[Find(t, cursor)];
    return segment.angle + Rotation(segment, t - segment.start_s);
  }

 private:
  double tau_;
  std::vector<SpeedSegment> segments_;
};

// A commanded wheel-speed target for the trajectory kind.
Eigen::Array2d DrawTarget(LaserTrajectory kind, double max_speed, Random* random) {
  // Magnitudes of at least a fifth of the maximum keep every segment informative.
  const auto magnitude = [&] { return random->Sign() * random->Uniform(0.2, 1.0) * max_speed; };
  switch (kind) {
    case LaserTrajectory::kStraight: {
      const double s = magnitude();
      return Eigen::Array2d(s, s);
    }
    case LaserTrajectory::kPureRotation: {
      const double s = magnitude();
      return Eigen::Array2d(-s, s);
    }
    case LaserTrajectory::kConstantArc:
      return Eigen::Array2d(0.6, 1.0) * max_speed;
    case LaserTrajectory::kRich:
      break;
  }
  const double choice = random->Uniform();
  const double s = magnitude();
  if (choice < 1.0 / 3.0) return Eigen::Array2d(s, s);
  if (choice < 2.0 / 3.0) return Eigen::Array2d(-s, s);
  // An arc: the faster wheel at s, the other anywhere in [−|s|, |s|] (curvature of either sign).
  const double other = s * random->Uniform(-1.0, 1.0);
  return random->Uniform() < 0.5 ? Eigen::Array2d(s, other) : Eigen::Array2d(other, s);
}

// Constant speeds: targets change only at interval boundaries, after ~Exponential(segment_mean_s)
// seconds of holding.
WheelProfile ConstantSpeedProfile(const LaserSimOptions& options,
                                  const std::vector<double>& boundaries) {
  Random random(options.seed, Stream::kTargets);
  std::vector<SpeedSegment> segments;
  const double hold_mean = std::max(options.segment_mean_s, 0.0);
  double next_change = 0.0;
  for (size_t k = 0; k + 1 < boundaries.size(); ++k) {
    const double t = boundaries[k];
    if (k > 0 && t < next_change) continue;
    const Eigen::Array2d target = DrawTarget(options.trajectory, options.max_wheel_speed, &random);
    next_change = t + random.Exponential(hold_mean);
    if (!segments.empty()) {
      const SpeedSegment& last = segments.back();
      if ((target == last.target).all()) continue;
      SpeedSegment segment;
      segment.start_s = t;
      segment.angle = last.angle + last.target * (t - last.start_s);
      segment.target = segment.speed = target;
      segments.push_back(segment);
    } else {
      SpeedSegment segment;
      segment.target = segment.speed = target;
      segments.push_back(segment);
    }
  }
  return WheelProfile(0.0, std::move(segments));
}

// Smooth speeds: a new target every ~Exponential(segment_mean_s) seconds, followed through the
// first-order lag. The profile starts at its first target and runs until `end_s`.
WheelProfile SmoothProfile(const LaserSimOptions& options, double end_s) {
  Random random(options.seed, Stream::kTargets);
  const double tau = options.speed_time_constant_s;
  const double hold_mean =
      options.segment_mean_s > 0.0 ? options.segment_mean_s : options.mean_interval_s;
  std::vector<SpeedSegment> segments(1);
  segments[0].target = segments[0].speed =
      DrawTarget(options.trajectory, options.max_wheel_speed, &random);
  const WheelProfile evaluator(tau, {});
  if (options.trajectory == LaserTrajectory::kConstantArc) {
    return WheelProfile(tau, std::move(segments));
  }
  double start = random.Exponential(hold_mean);
  while (start < end_s) {
    const SpeedSegment& last = segments.back();
    SpeedSegment segment;
    segment.start_s = start;
    segment.speed = evaluator.Speed(last, start - last.start_s);
    segment.angle = last.angle + evaluator.Rotation(last, start - last.start_s);
    segment.target = DrawTarget(options.trajectory, options.max_wheel_speed, &random);
    segments.push_back(segment);
    start += random.Exponential(hold_mean);
  }
  return WheelProfile(tau, std::move(segments));
}

struct Radii {
  double left = 0.0;
  double right = 0.0;
  double base = 0.0;
  // (v, ω) from wheel speeds (or their derivatives, for dv/dt).
  double Forward(const Eigen::Array2d& phi) const { return 0.5 * (left * phi(0) + right * phi(1)); }
  double Angular(const Eigen::Array2d& phi) const {
    return (right * phi(1) - left * phi(0)) / base;
  }
};

// exp of the constant body twist (u, w, ω) held for dt.
Pose2d TwistExp(double u, double w, double omega, double dt) {
  return Exp(Twist2d(u * dt, w * dt, omega * dt));
}

// The robot's motion over each scan window [t_k + δ, t_{k+1} + δ], never storing the path.
class RobotIntegrator {
 public:
  RobotIntegrator(const LaserSimOptions& options, const WheelProfile& profile)
      : profile_(profile),
        effects_(options.effects),
        before_{options.odometry.left_radius_m, options.odometry.right_radius_m,
                options.odometry.wheelbase_m},
        after_{options.effects.left_radius_after_m, options.effects.right_radius_after_m,
               options.odometry.wheelbase_m},
        change_s_(options.effects.radius_change_time_s >= 0.0 ? options.effects.radius_change_time_s
                                                              : kInfinity) {
    if (profile_.smooth()) {
      // The fastest turning rate sets the heading's time scale (see the top of the file).
      double omega_max = 0.0;
      for (const Radii& radii : {before_, after_}) {
        if (radii.base != 0.0) {
          omega_max =
              std::max(omega_max, (std::abs(radii.left) + std::abs(radii.right)) *
                                      std::abs(options.max_wheel_speed) / std::abs(radii.base));
        }
      }
      const double scale =
          omega_max > 0.0 ? std::min(profile_.tau(), 1.0 / omega_max) : profile_.tau();
      panel_s_ = std::max(options.integration_step_s, 0.5 * scale);
    }
  }

  std::vector<Pose2d> Integrate(const std::vector<double>& boundaries) const {
    const std::vector<SpeedSegment>& segments = profile_.segments();
    const double offset = effects_.time_offset_s;
    const size_t num_intervals = boundaries.size() - 1;
    std::vector<Pose2d> motions;
    motions.reserve(num_intervals);
    double t = boundaries[0] + offset;
    size_t cursor = 0;
    size_t segment = profile_.Find(t, &cursor);
    Pose2d motion = Pose2d::Zero();  // Since the last scan, in the robot frame at that scan.
    while (motions.size() < num_intervals) {
      const double next_scan = boundaries[motions.size() + 1] + offset;
      const double next_segment =
          segment + 1 < segments.size() ? segments[segment + 1].start_s : kInfinity;
      const double next_change = change_s_ > t ? change_s_ : kInfinity;
      const double next = std::min({next_scan, next_segment, next_change});
      if (next > t) {
        const Radii& radii = 0.5 * (t + next) < change_s_ ? before_ : after_;
        motion = profile_.smooth()
                     ? Compose(motion, SmoothPiece(segments[segment], radii, t, next))
                     : Compose(motion, ConstantPiece(segments[segment], radii, next - t));
      }
      t = next;
      Pose2d impulse = Pose2d::Zero();
      if (t == next_segment) {
        ++segment;
        if (!profile_.smooth() && effects_.longitudinal_slip_s != 0.0) {
          const Radii& radii = t < change_s_ ? before_ : after_;
          const double jump =
              radii.Forward(segments[segment].target) - radii.Forward(segments[segment - 1].target);
          impulse(0) = -effects_.longitudinal_slip_s * jump;
        }
      }
      if (t == next_scan) {
        // A scan at the instant of an impulse sees half of it (the centred-ramp convention).
        motions.push_back(Compose(motion, Pose2d(0.5 * impulse)));
        motion = 0.5 * impulse;
      } else {
        motion = Compose(motion, impulse);
      }
    }
    return motions;
  }

 private:
  Pose2d ConstantPiece(const SpeedSegment& segment, const Radii& radii, double dt) const {
    const double v = radii.Forward(segment.target);
    const double omega = radii.Angular(segment.target);
    return TwistExp(v, effects_.lateral_slip_s * v * omega, omega, dt);
  }

  // The motion over [a, b] inside one segment, in the robot frame at a: the heading is closed
  // form and the position ∫ R(θ)·(u, w) dt a 4-point Gauss–Legendre sum per panel.
  Pose2d SmoothPiece(const SpeedSegment& segment, const Radii& radii, double a, double b) const {
    static constexpr double kNodes[4] = {-0.8611363115940526, -0.3399810435848563,
                                         0.3399810435848563, 0.8611363115940526};
    static constexpr double kWeights[4] = {0.3478548451374538, 0.6521451548625461,
                                           0.6521451548625461, 0.3478548451374538};
    const double tau = profile_.tau();
    const Eigen::Array2d lag = segment.speed - segment.target;
    const Eigen::Array2d rotation_a = profile_.Rotation(segment, a - segment.start_s);
    const auto relative_heading = [&](double dt) {
      return radii.Angular(profile_.Rotation(segment, dt) - rotation_a);
    };
    const int panels = std::max(1, static_cast<int>(std::ceil((b - a) / panel_s_)));
    const double h = (b - a) / panels;
    double x = 0.0;
    double y = 0.0;
    for (int p = 0; p < panels; ++p) {
      double px = 0.0;
      double py = 0.0;
      for (int i = 0; i < 4; ++i) {
        const double dt = a + h * (p + 0.5 * (1.0 + kNodes[i])) - segment.start_s;
        const double decay = std::exp(-std::max(dt, 0.0) / tau);
        // Φ − Φ(a) = g·dt + (φ_a − g)·τ·(1 − e), φ = g + (φ_a − g)·e, dφ/dt = −(φ_a − g)·e/τ.
        const Eigen::Array2d rotation =
            segment.target * dt + lag * (tau * (1.0 - decay)) - rotation_a;
        const Eigen::Array2d speed = segment.target + lag * decay;
        const Eigen::Array2d accel = lag * (-decay / tau);
        const double v = radii.Forward(speed);
        const double omega = radii.Angular(speed);
        const double u = v - effects_.longitudinal_slip_s * radii.Forward(accel);
        const double w = effects_.lateral_slip_s * v * omega;
        const double theta = radii.Angular(rotation);
        const double c = std::cos(theta);
        const double s = std::sin(theta);
        px += kWeights[i] * (c * u - s * w);
        py += kWeights[i] * (s * u + c * w);
      }
      x += 0.5 * h * px;
      y += 0.5 * h * py;
    }
    return Pose2d(x, y, relative_heading(b - segment.start_s));
  }

  const WheelProfile& profile_;
  LaserEffects effects_;
  Radii before_;
  Radii after_;
  double change_s_;
  double panel_s_ = kInfinity;
};

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
    simulation.profile = options.speed_time_constant_s > 0.0
                             ? SmoothProfile(options, end_s)
                             : ConstantSpeedProfile(options, simulation.boundaries);
    const std::vector<Pose2d> robot_motions =
        RobotIntegrator(options, simulation.profile).Integrate(simulation.boundaries);
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
