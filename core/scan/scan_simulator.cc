#include <calib/core/laser/robot_integrator.h>
#include <calib/core/laser/wheel_profile.h>
#include <calib/core/random.h>
#include <calib/core/scan/scan_simulator.h>
#include <calib/core/text_number.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

// How it works: the wheel profile is the laser simulator's (same seed stream, so the same wheel
// angles), and the robot's pose at a time t is the pose at the latest scan time before t (those
// "knots" chained from IntegrateRobotMotions) composed with the integrated motion from the knot to
// t. A scan asks for all its beam times at once, so one integrator pass serves a whole sweep.
namespace calib {
namespace scan_sim_internal {

struct PathData {
  LaserSimOptions options;  // effects.time_offset_s zeroed: knots are true times already.
  laser_sim_internal::WheelProfile profile{0.0, {}};
  std::vector<double> knots;
  std::vector<Pose2d> world_T_base;  // At the knots.
};

}  // namespace scan_sim_internal

namespace {

using scan_sim_internal::PathData;

// The laser simulator's stream of commanded targets (laser_simulator.cc, Stream::kTargets).
constexpr uint32_t kLaserTargetsStream = 2;
enum Stream : uint32_t { kRangeNoise = 1, kMissing };

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// `samples`: the scan times as the laser simulator takes its interval boundaries (before the time
// offset); the profile runs at least until end_s.
std::shared_ptr<const PathData> MakePath(const LaserSimOptions& laser,
                                         const std::vector<double>& samples, double end_s) {
  auto data = std::make_shared<PathData>();
  data->options = laser;
  data->options.effects.time_offset_s = 0.0;
  Random targets(laser.seed, kLaserTargetsStream);
  data->profile = laser.speed_time_constant_s > 0.0
                      ? laser_sim_internal::SmoothProfile(data->options, end_s, &targets)
                      : laser_sim_internal::ConstantSpeedProfile(data->options, samples, &targets);
  for (const double t : samples) data->knots.push_back(t + laser.effects.time_offset_s);
  const std::vector<Pose2d> motions =
      laser_sim_internal::IntegrateRobotMotions(data->options, data->profile, data->knots);
  data->world_T_base.push_back(Pose2d::Zero());
  for (const Pose2d& motion : motions) {
    data->world_T_base.push_back(Compose(data->world_T_base.back(), motion));
  }
  return data;
}

Pose2d MotionBetween(const PathData& data, double a, double b) {
  return laser_sim_internal::IntegrateRobotMotions(data.options, data.profile, {a, b})[0];
}

}  // namespace

Pose2d RobotPath::WorldTBase(double t_s) const { return WorldTBase(std::vector<double>{t_s})[0]; }

std::vector<Pose2d> RobotPath::WorldTBase(const std::vector<double>& times_s) const {
  std::vector<Pose2d> poses;
  if (data_ == nullptr || data_->knots.empty()) {
    poses.assign(times_s.size(), Pose2d::Zero());
    return poses;
  }
  const PathData& data = *data_;
  poses.reserve(times_s.size());
  size_t i = 0;
  while (i < times_s.size()) {
    const double t = times_s[i];
    if (!(t >= data.knots[0])) {  // Before the first knot (or NaN): integrate back to it.
      poses.push_back(std::isfinite(t) ? Compose(data.world_T_base[0],
                                                 Inverse(MotionBetween(data, t, data.knots[0])))
                                       : Pose2d::Zero());
      ++i;
      continue;
    }
    const size_t k =
        std::upper_bound(data.knots.begin(), data.knots.end(), t) - data.knots.begin() - 1;
    const double knot_end = k + 1 < data.knots.size() ? data.knots[k + 1] : kInfinity;
    std::vector<double> boundaries{data.knots[k]};
    while (i < times_s.size() && times_s[i] >= boundaries.back() && times_s[i] < knot_end) {
      boundaries.push_back(times_s[i++]);
    }
    if (boundaries.size() == 1) {  // Decreasing times: one at a time.
      boundaries.push_back(times_s[i++]);
    }
    Pose2d pose = data.world_T_base[k];
    for (const Pose2d& motion :
         laser_sim_internal::IntegrateRobotMotions(data.options, data.profile, boundaries)) {
      pose = Compose(pose, motion);
      poses.push_back(pose);
    }
  }
  return poses;
}

LaserSimOptions DefaultScanLaserOptions() {
  LaserSimOptions options;
  options.odometry = OdometryParams{0.1, 0.1, 0.5};
  options.base_T_sensor = Pose2d(0.2, 0.05, 0.1);
  options.num_intervals = 100;
  options.mean_interval_s = 0.1;
  options.interval_jitter_s = 0.0;
  options.max_wheel_speed = 5.0;  // 0.5 m/s.
  options.speed_time_constant_s = 0.5;
  options.segment_mean_s = 3.0;
  return options;
}

void AddMastAndGuard(ScanSimOptions* options) {
  const double deg = M_PI / 180.0;
  options->body.push_back({130.0 * deg, 140.0 * deg, 0.15});
  options->body.push_back({-140.0 * deg, -130.0 * deg, 0.15});
  options->body.push_back({170.0 * deg, 190.0 * deg, 0.25});
}

namespace {

Status CheckScanOptions(const ScanSimOptions& o) {
  const auto fail = [](const std::string& what) {
    return Status::InvalidInput("scan simulator: " + what);
  };
  if (o.beams < 1 || o.beams > 100000) {
    return fail("beams must be in [1, 100000], got " + std::to_string(o.beams));
  }
  if (!(o.field_of_view_rad > 0.0 && o.field_of_view_rad <= 2.0 * M_PI + 1e-12)) {
    return fail("field_of_view_rad must be in (0, 2π], got " + Num(o.field_of_view_rad));
  }
  if (!(o.range_min_m >= 0.0 && o.range_max_m > o.range_min_m && std::isfinite(o.range_max_m))) {
    return fail("need 0 <= range_min_m < range_max_m < inf, got " + Num(o.range_min_m) + ", " +
                Num(o.range_max_m));
  }
  if (!(o.range_noise_sigma_m >= 0.0 && std::isfinite(o.range_noise_sigma_m))) {
    return fail("range_noise_sigma_m must be finite and >= 0, got " + Num(o.range_noise_sigma_m));
  }
  if (!(o.missing_probability >= 0.0 && o.missing_probability <= 1.0)) {
    return fail("missing_probability must be in [0, 1], got " + Num(o.missing_probability));
  }
  if (!(o.sweep_s >= 0.0 && std::isfinite(o.sweep_s))) {
    return fail("sweep_s must be finite and >= 0, got " + Num(o.sweep_s));
  }
  if (!(o.encoder_rate_hz >= 0.0 && o.encoder_rate_hz <= 1e5)) {
    return fail("encoder_rate_hz must be in [0, 1e5], got " + Num(o.encoder_rate_hz));
  }
  const LaserSimOptions& l = o.laser;
  if (l.num_intervals < 1 || l.num_intervals > 1000000 || !(l.mean_interval_s > 0.0) ||
      !std::isfinite(l.mean_interval_s)) {
    return fail("laser.num_intervals must be in [1, 1e6] and laser.mean_interval_s > 0, got " +
                std::to_string(l.num_intervals) + ", " + Num(l.mean_interval_s));
  }
  if (static_cast<double>(l.num_intervals + 1) * o.beams > 2e8) {
    return fail("scans × beams exceeds 2e8");
  }
  if (o.logging.has_value()) CALIB_RETURN_IF_ERROR(ValidateLoggingModel(*o.logging));
  return Status::Ok();
}

// The scans' stamps, their sweeps' sample times (before the time offset), every sensor sample and
// the encoders, from the laser simulator's own streams.
struct ScanTiming {
  std::vector<double> stamps_s, sample_s, all_samples_s;
  // Per row: which sample it holds (a logger faster than the sensor writes one twice).
  std::vector<size_t> sample_index;
  std::vector<EncoderSample> encoders;
};

ScanTiming MakeTiming(const ScanSimOptions& options) {
  ScanTiming timing;
  LaserStreams streams;
  if (options.logging.has_value()) {
    LoggedTimingTruth logged;
    streams = SimulateLoggedLaserStreams(options.laser, *options.logging, nullptr, &logged);
    timing.sample_s = logged.sensor_sample_time_s;
    timing.sample_index = logged.sensor_sample_index;
    timing.all_samples_s = logged.all_sensor_sample_times_s;
  } else {
    streams = SimulateLaserStreams(options.laser, options.encoder_rate_hz);
    for (const StampedPose& pose : streams.sensor_poses) {
      timing.sample_index.push_back(timing.sample_s.size());
      timing.sample_s.push_back(pose.t_s);
    }
    timing.all_samples_s = timing.sample_s;
  }
  for (const StampedPose& pose : streams.sensor_poses) timing.stamps_s.push_back(pose.t_s);
  timing.encoders = std::move(streams.odometry);
  return timing;
}

// Robot positions (base and sensor) every 0.05 s over [begin, end], for the world builder.
std::vector<Eigen::Vector2d> Footprint(const RobotPath& path, const Pose2d& base_T_sensor,
                                       double begin_s, double end_s) {
  std::vector<double> times;
  const int n = static_cast<int>(std::ceil((end_s - begin_s) / 0.05)) + 1;
  for (int j = 0; j <= n; ++j) times.push_back(std::min(begin_s + 0.05 * j, end_s));
  std::vector<Eigen::Vector2d> points;
  for (const Pose2d& pose : path.WorldTBase(times)) {
    points.push_back(pose.head<2>());
    points.push_back(Compose(pose, base_T_sensor).head<2>());
  }
  return points;
}

}  // namespace

StatusOr<ScanSimulation> SimulateScans(const ScanSimOptions& options) {
  CALIB_RETURN_IF_ERROR(CheckScanOptions(options));
  ScanTiming timing = MakeTiming(options);
  if (timing.sample_s.empty()) return Status::InvalidInput("scan simulator: no scan was taken");
  const double offset_s = options.laser.effects.time_offset_s;
  double end_s = timing.all_samples_s.back();
  for (const double t : timing.stamps_s) end_s = std::max(end_s, t);
  if (!timing.encoders.empty()) end_s = std::max(end_s, timing.encoders.back().t_s);
  end_s += std::abs(offset_s) + options.sweep_s + 1.0;

  ScanSimulation sim;
  sim.encoders = std::move(timing.encoders);
  ScanSimTruth& truth = sim.truth;
  truth.odometry = options.laser.odometry;
  truth.base_T_sensor = options.laser.base_T_sensor;
  truth.effects = options.laser.effects;
  truth.path = RobotPath(MakePath(options.laser, timing.all_samples_s, end_s));

  const int n = options.beams;
  const double time_increment = options.sweep_s / n;
  const bool full_circle = options.field_of_view_rad >= 2.0 * M_PI - 1e-12;
  const double increment = n == 1 ? 0.0 : options.field_of_view_rad / (full_circle ? n : n - 1);
  const double last_sweep_s = timing.sample_s.back() + offset_s + options.sweep_s;
  CALIB_ASSIGN_OR_RETURN(
      sim.world, BuildScanWorld(Footprint(truth.path, truth.base_T_sensor,
                                          timing.all_samples_s.front() + offset_s, last_sweep_s),
                                options.world));

  Random noise(options.seed, kRangeNoise);
  Random missing(options.seed, kMissing);
  const float no_return = options.missing_as_nan ? std::numeric_limits<float>::quiet_NaN()
                                                 : std::numeric_limits<float>::infinity();
  std::vector<double> beam_times(time_increment > 0.0 ? n : 1);
  // Upside down, a beam at angle a in the lidar's frame looks along −a in the upright one.
  const double mirror = options.upside_down ? -1.0 : 1.0;
  truth.upside_down = options.upside_down;
  sim.scans.reserve(timing.sample_s.size());
  for (size_t k = 0; k < timing.sample_s.size(); ++k) {
    LaserScan scan;
    scan.stamp_s = scan.log_time_s = timing.stamps_s[k];
    scan.angle_min_rad = -0.5 * options.field_of_view_rad;
    scan.angle_increment_rad = increment;
    scan.time_increment_s = time_increment;
    scan.scan_time_s = options.laser.mean_interval_s;
    if (options.logging.has_value() && options.logging->sensor_period_s > 0.0) {
      scan.scan_time_s = options.logging->sensor_period_s;
    }
    scan.range_min_m = options.range_min_m;
    scan.range_max_m = options.range_max_m;
    scan.frame_id = options.frame_id;
    scan.record = static_cast<int64_t>(k);
    const double start_s = timing.sample_s[k] + offset_s;
    for (size_t i = 0; i < beam_times.size(); ++i) beam_times[i] = start_s + i * time_increment;
    const std::vector<Pose2d> bases = truth.path.WorldTBase(beam_times);
    truth.sweep_start_s.push_back(start_s);
    truth.world_T_sensor.push_back(Compose(bases[0], truth.base_T_sensor));
    // A held sample is written again as it was: the same ranges under a new stamp.
    if (k > 0 && timing.sample_index[k] == timing.sample_index[k - 1]) {
      scan.ranges_m = sim.scans.back().ranges_m;
      sim.scans.push_back(std::move(scan));
      continue;
    }
    scan.ranges_m.resize(n);
    for (int i = 0; i < n; ++i) {
      const Pose2d sensor = Compose(bases[time_increment > 0.0 ? i : 0], truth.base_T_sensor);
      double range = sim.world.CastRay(sensor.head<2>(), sensor(2) + mirror * scan.BeamAngle(i),
                                       options.range_max_m);
      for (const ScanSimOptions::BodySector& b : options.body) {
        const double a = std::remainder(scan.BeamAngle(i) - b.from_rad, 2.0 * M_PI);
        const double width = std::remainder(b.to_rad - b.from_rad, 2.0 * M_PI);
        // [from, to), robust to the rounding of angles that fall on its ends.
        if (a > -1e-9 && a < width - 1e-9) range = std::min(range, b.range_m);
      }
      range += options.range_noise_sigma_m * noise.Normal();  // Drawn for every beam.
      const bool dropped = missing.Uniform() < options.missing_probability;
      const bool valid = !dropped && range >= options.range_min_m && range <= options.range_max_m;
      scan.ranges_m[i] = valid ? static_cast<float>(range) : no_return;
    }
    sim.scans.push_back(std::move(scan));
  }
  return sim;
}

RobotMessages ScanSimulationMessages(const ScanSimulation& simulation,
                                     const RobotMessageNames& names) {
  RobotMessages messages;
  messages.source = "simulation";
  const double epoch = names.epoch_s;
  std::vector<LaserScan>& scans = messages.scans[names.scan_topic];
  for (LaserScan scan : simulation.scans) {
    scan.stamp_s += epoch;
    scan.log_time_s += epoch;
    scans.push_back(std::move(scan));
  }
  std::vector<JointState>& joints = messages.joint_states[names.joint_topic];
  std::vector<Odometry>& odometry = messages.odometry[names.odom_topic];
  const OdometryParams& p = simulation.truth.odometry;
  Pose2d pose = Pose2d::Zero();
  for (size_t j = 0; j < simulation.encoders.size(); ++j) {
    const EncoderSample& e = simulation.encoders[j];
    JointState joint;
    joint.stamp_s = joint.log_time_s = e.t_s + epoch;
    joint.record = static_cast<int64_t>(j);
    joint.name = {names.left_joint, names.right_joint};
    joint.position = {e.left_rad, e.right_rad};
    joints.push_back(std::move(joint));
    if (j > 0) {
      const EncoderSample& a = simulation.encoders[j - 1];
      pose =
          Compose(pose, WheelStepDisplacement(p.left_radius_m, p.right_radius_m, p.wheelbase_m,
                                              e.left_rad - a.left_rad, e.right_rad - a.right_rad));
    }
    Odometry odom;
    odom.stamp_s = odom.log_time_s = joints.back().stamp_s;
    odom.record = static_cast<int64_t>(j);
    odom.frame_id = names.odom_frame;
    odom.child_frame_id = names.base_frame;
    odom.position = Eigen::Vector3d(pose(0), pose(1), 0.0);
    odom.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(pose(2), Eigen::Vector3d::UnitZ()));
    odometry.push_back(odom);
  }
  TransformStamped mount;
  const double start = simulation.scans.empty() ? 0.0 : simulation.scans.front().stamp_s;
  mount.stamp_s = mount.log_time_s = start + epoch;
  mount.parent_frame = names.base_frame;
  mount.child_frame = simulation.scans.empty() ? "laser" : simulation.scans.front().frame_id;
  const Pose2d& l = simulation.truth.base_T_sensor;
  mount.translation = Eigen::Vector3d(l(0), l(1), 0.0);
  mount.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(l(2), Eigen::Vector3d::UnitZ()));
  if (simulation.truth.upside_down) {
    mount.rotation =
        mount.rotation * Eigen::Quaterniond(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()));
  }
  messages.tf_static.push_back(mount);
  for (const auto& [topic, list] : messages.scans) {
    messages.topics.push_back({topic, "sensor_msgs/LaserScan", static_cast<int64_t>(list.size())});
  }
  messages.topics.push_back(
      {names.joint_topic, "sensor_msgs/JointState", static_cast<int64_t>(joints.size())});
  messages.topics.push_back(
      {names.odom_topic, "nav_msgs/Odometry", static_cast<int64_t>(odometry.size())});
  messages.topics.push_back({"/tf_static", "tf2_msgs/TFMessage", 1});
  return messages;
}

}  // namespace calib
