#include <calib/tools/commands/flags.h>
#include <gflags/gflags.h>

// Defaults come from the options structs, so that the flags and the structs cannot disagree.
namespace {
const calib::cli::DiagnoseOptions kDiagnose;
const calib::cli::SimulateOptions kSimulate;
}  // namespace

DEFINE_string(input, "",
              "A laser log file (tuples or CSV), a laser raw-stream directory, a robot's bag "
              "(ROS 2 .mcap or .db3 or bag directory, ROS 1 .bag), several laser logs "
              "separated by commas (calibrated jointly), or a bearing log directory "
              "(odometry.csv, bearings.csv, meta.json)");
DEFINE_string(output, "",
              "Where to write the JSON result (optional: without it only the summary is "
              "printed; - writes the JSON on stdout and the summary on stderr)");
DEFINE_string(format, kDiagnose.format.c_str(), "Laser log format: auto, tuples, csv or stream");
DEFINE_string(loss, kDiagnose.loss.c_str(), "Robust loss: cauchy, huber, tukey or none");
DEFINE_double(loss_scale, kDiagnose.loss_scale,
              "Scale of the robust loss, in whitened residual units");
DEFINE_double(redescending_scale, calib::cli::CalibrateOptions().redescending_scale,
              "calibrate (laser): after the fit under --loss, refit under Tukey's biweight at "
              "this scale (whitened units), so that gross slips leave no bias on long logs; "
              "0 keeps the first loss");
DEFINE_bool(quiet, kDiagnose.quiet, "Do not print the summary on stdout");
DEFINE_string(timing, kDiagnose.timing.c_str(),
              "calibrate, diagnose (raw laser streams): auto estimates every sample's true time "
              "with the calibration (the sensor clock model chosen by the data), stamps or "
              "free_running force that clock model, off takes the stamps as sample times; "
              "diagnose then searches on the intervals between the estimated times");

// `calib calibrate` on a robot's bag.
DEFINE_string(
    scan_topic, "",
    "calibrate, diagnose (bags): the sensor_msgs/LaserScan topic (default: the only one)");
DEFINE_string(
    joint_state_topic, "",
    "calibrate, diagnose (bags): the sensor_msgs/JointState topic of the wheels (default: the one "
    "whose joints name a left and a right wheel)");
DEFINE_string(left_wheel_joint, "", "calibrate, diagnose (bags): the left wheel's joint name");
DEFINE_string(right_wheel_joint, "", "calibrate, diagnose (bags): the right wheel's joint name");
DEFINE_string(
    odom_topic, "",
    "calibrate, diagnose (bags): the nav_msgs/Odometry topic whose poses give the wheel angles "
    "when no JointState names the wheels (needs the nominal wheels)");
DEFINE_double(nominal_wheel_radius, 0.0,
              "calibrate, diagnose (bags): the wheel radius (m) the robot's driver uses; with "
              "--nominal_wheelbase it seeds the scan matching and, for wheel angles from "
              "odometry, the result gives corrections to it");
DEFINE_double(nominal_wheelbase, 0.0,
              "calibrate, diagnose (bags): the wheelbase (m) the driver uses");
DEFINE_string(encoder_topic, "",
              "calibrate, diagnose (bags): a topic of the robot's own message type whose fields "
              "hold the wheels' raw encoder counts (read through the message definition the bag "
              "stores; default: a known type's topic, e.g. turtlebot3_msgs/SensorState, when no "
              "JointState names the wheels); with --ticks_per_rev unless the type is known");
DEFINE_string(left_encoder_field, "",
              "calibrate, diagnose (bags): the field of --encoder_topic's message with the left "
              "wheel's counts (a.b for a nested one; default: the known type's)");
DEFINE_string(right_encoder_field, "",
              "calibrate, diagnose (bags): the field with the right wheel's counts");
DEFINE_double(lidar_rotation_period, 0.0,
              "calibrate, diagnose (bags, scan directories): the time (s) the lidar takes to turn "
              "once (0.1 for 10 Hz), for scans whose driver leaves time_increment 0: each beam is "
              "then placed at its own time (period × angle_increment / 2π after the previous), so "
              "that the sweeps are de-skewed; scans with a time_increment keep theirs");
DEFINE_string(
    lidar_beam_timing, "auto",
    "calibrate, diagnose (bags, scan directories): auto checks a full-circle lidar's beam "
    "order and time_increment against the scans of the fastest turns (where each sweep "
    "closes, only the right timing makes its first and last beams continue each other's "
    "walls) and uses the timing they show, with a warning, when the driver's clearly "
    "loses (the LDS-01's driver lists its beams against their order); driver trusts the "
    "driver's");
DEFINE_string(lidar_self_returns, "mask",
              "calibrate, diagnose (bags, scan directories, CSM logs): mask leaves out the beams "
              "that return from one short range (< 1 m) in scan after scan while the scene moves "
              "(the robot's own posts, guard or chassis in the lidar's view), with a note; keep "
              "matches them");
DEFINE_double(lidar_min_range, 0.0,
              "calibrate, diagnose (bags, scan directories, CSM logs): ranges (m) nearer than "
              "this are no return, whatever the scans' range_min says (parts of the robot, a "
              "lidar's error codes)");
DEFINE_string(base_frame, "",
              "calibrate, diagnose (bags): the robot's base frame in tf (default base_link, else "
              "base_footprint)");
DEFINE_string(
    wheel_angle_unit, "rad",
    "calibrate, diagnose (every laser input: bags, scan directories, streams, interval logs): the "
    "unit of the wheel readings (angles, or speeds per second): rad, deg, or ticks:N for raw "
    "encoder counts of N per wheel turn");
DEFINE_double(ticks_per_rev, 0.0,
              "calibrate, diagnose (laser logs, streams, bags): the wheel readings are encoder "
              "ticks, this many per wheel turn; they are converted to radians (for bags the same "
              "as --wheel_angle_unit ticks:N)");
DEFINE_string(export, "",
              "calibrate: also write the calibration for deployment, beside the JSON (OUT.yaml, "
              "OUT.urdf, OUT.tf) or as calib_calibration.* in the working directory: yaml "
              "(diff_drive_controller parameters, the sensor mounting, the time offset), urdf "
              "(the sensor's joint origin), tf (static_transform_publisher arguments), "
              "comma-separated, or all");
DEFINE_bool(scan_points, false,
            "calibrate (bags, scan directories): refine the calibration against the scan points "
            "themselves (point-to-line distances between neighbouring scans, each beam placed "
            "at its own time through the calibrated odometry) after matching them");

// `calib diagnose`.
DEFINE_double(family_alpha, kDiagnose.family_alpha,
              "diagnose: family-wise error rate of each forward step (Holm over the candidates)");
DEFINE_int32(max_effects, kDiagnose.max_effects, "diagnose: at most this many effects adopted");
DEFINE_int32(cv_blocks, kDiagnose.cv_blocks,
             "diagnose: contiguous held-out blocks for the cross-validation");
DEFINE_string(candidates, "",
              "diagnose: comma-separated candidate effects (default all: time_offset, "
              "lateral_slip, longitudinal_slip, wheel_radius_change, speed_dependent_radius, "
              "icr_offset_x, scan_scale)");
DEFINE_string(boundary_speeds, kDiagnose.boundary_speeds.c_str(),
              "diagnose: wheel speeds at interval boundaries: auto, piecewise (constant within "
              "intervals) or smooth");
DEFINE_string(plots_dir, "",
              "folder for the plots: calibrate draws its plots (dead reckoning, residuals, "
              "coverage) only when given; diagnose draws its residual profiles there (default: "
              "OUT_plots next to the JSON output)");
DEFINE_string(plot_format, "svg",
              "format of the plots: svg, or png (each SVG also converted to PNG by rsvg-convert, "
              "Debian package librsvg2-bin)");

// `calib simulate`: a laser log with known truth.
DEFINE_string(truth, "", "simulate: where to write the truth as JSON (optional)");
DEFINE_int32(intervals, kSimulate.intervals, "simulate: number of intervals");
DEFINE_uint64(seed, kSimulate.seed, "simulate: random seed");
DEFINE_string(trajectory, kSimulate.trajectory.c_str(),
              "simulate: rich, straight, rotation or arc");
DEFINE_double(noise_xy, kSimulate.noise_xy, "simulate: scan-matching noise sigma on x and y (m)");
DEFINE_double(noise_theta, kSimulate.noise_theta,
              "simulate: scan-matching noise sigma on theta (rad)");
DEFINE_double(outliers, kSimulate.outliers, "simulate: fraction of slip outliers");
DEFINE_double(speed_time_constant, kSimulate.speed_time_constant,
              "simulate: wheel speeds follow their targets with this lag (s); 0: speeds constant "
              "within each interval");
DEFINE_double(segment_mean, kSimulate.segment_mean,
              "simulate: mean time between new speed targets (s)");
DEFINE_double(max_wheel_speed, kSimulate.max_wheel_speed,
              "simulate: largest commanded wheel speed (rad/s)");
DEFINE_double(time_offset, kSimulate.time_offset,
              "A sensor sample stamped t was taken at t + this (s) on the odometry clock: "
              "calibrate and diagnose apply it to the sensor's stamps (raw streams, bags, bearing "
              "logs; not interval logs) as a known latency; simulate writes it into the log");
DEFINE_double(lateral_slip, kSimulate.lateral_slip,
              "simulate: lateral velocity = this * v * omega (s)");
DEFINE_double(longitudinal_slip, kSimulate.longitudinal_slip,
              "simulate: forward velocity = v - this * dv/dt (s)");
DEFINE_double(radius_change_time, kSimulate.radius_change_time,
              "simulate: time of a wheel-radius change (s), < 0: none");
DEFINE_double(r_l_after, kSimulate.r_l_after, "simulate: left radius after the change (m)");
DEFINE_double(r_r_after, kSimulate.r_r_after, "simulate: right radius after the change (m)");
// `calib simulate`: scan timing and the logging model (core/timing/logging_model.h). Output
// format (--format auto): OUTPUT ending in .csv is a CSV log, OUTPUT without an extension a raw
// stream directory (odometry.csv, sensor_poses.csv), anything else tuples.
DEFINE_double(mean_interval, kSimulate.mean_interval,
              "simulate: mean scan interval (s), when the sensor does not free-run");
DEFINE_double(interval_jitter, kSimulate.interval_jitter,
              "simulate: uniform +/- jitter on each scan interval (s)");
DEFINE_double(sensor_period, kSimulate.sensor_period,
              "simulate (streams; the logging flags need --format stream or an OUTPUT without "
              "extension): the sensor free-runs at this period (s) for --intervals periods; "
              "0: it samples at the simulated scan times");
DEFINE_double(sensor_phase, kSimulate.sensor_phase,
              "simulate (streams): time of the free-running sensor's first sample (s)");
DEFINE_double(sensor_drift, kSimulate.sensor_drift,
              "simulate (streams): relative rate error of the sensor clock (e.g. 2e-4); its "
              "true period is sensor_period * (1 + drift)");
DEFINE_double(logger_period, kSimulate.logger_period,
              "simulate (streams): a logger picks up the latest sensor sample at this period "
              "(s) and stamps it with the pick-up time; 0: every sample written once");
DEFINE_double(logger_jitter, kSimulate.logger_jitter,
              "simulate (streams): sigma of the pick-up times (s), at most 0.15 logger_period; "
              "without a logger, sigma of the sensor stamps");
DEFINE_double(pickup_latency, kSimulate.pickup_latency,
              "simulate (streams): fixed delay before a sample can be picked up (s)");
DEFINE_double(encoder_period, kSimulate.encoder_period,
              "simulate (streams): the encoders are polled at this period (s); 0: at the sensor "
              "sample times");
DEFINE_double(encoder_poll_jitter, kSimulate.encoder_poll_jitter,
              "simulate (streams): sigma of the true encoder poll times (s), at most 0.08 "
              "encoder_period");
DEFINE_double(encoder_stamp_jitter, kSimulate.encoder_stamp_jitter,
              "simulate (streams): sigma of the encoder stamps about the true poll times (s), at "
              "most 0.08 encoder_period");
DEFINE_double(repeat_fraction, kSimulate.repeat_fraction,
              "simulate (streams): share of records written twice (exact duplicate rows), < 0.5");

DEFINE_int32(beams, kSimulate.beams,
             "simulate (scans): beams per scan; > 0 simulates a lidar robot's raw scans in a "
             "world of walls (0.1 m wheels, 0.5 m wheelbase, 10 Hz scans, up to 0.5 m/s; "
             "--intervals, --seed, --trajectory, the effect and logging flags apply, and the "
             "motion flags when given) and writes "
             "OUT.json (the bag generators' robot messages), OUT.log (a CSM laser log with wheel "
             "encoder counts, as Censi et al.'s Khepera logged them) or a directory with "
             "odometry.csv and scans.csv");
DEFINE_double(field_of_view, kSimulate.field_of_view_deg,
              "simulate (scans): field of view (degrees)");
DEFINE_double(range_noise, kSimulate.range_noise, "simulate (scans): range noise sigma (m)");
DEFINE_double(missing_returns, kSimulate.missing_returns,
              "simulate (scans): share of beams without a return");
DEFINE_double(sweep, kSimulate.sweep,
              "simulate (scans): duration of one sweep (s); each beam is cast at its own time");
DEFINE_bool(self_returns, kSimulate.self_returns,
            "simulate (scans): parts of the robot in the lidar's view (posts at ±135° and a guard "
            "behind, 0.15–0.25 m away: 11 % of a full circle's beams)");
DEFINE_bool(upside_down, kSimulate.upside_down,
            "simulate (scans): the lidar is mounted upside down (its scans turn clockwise seen "
            "from the base; tf says so: OUT.json only)");
DEFINE_string(world, kSimulate.world.c_str(),
              "simulate (scans): rooms, corridor, clutter or mixed");

namespace calib::cli {

void ParseFlags(const char* usage, int* argc, char*** argv) {
  gflags::SetUsageMessage(usage);
  gflags::ParseCommandLineFlags(argc, argv, true);
}

CalibrateOptions CalibrateOptionsFromFlags() {
  CalibrateOptions options;
  options.input = FLAGS_input;
  options.output = FLAGS_output;
  options.format = FLAGS_format;
  options.loss = FLAGS_loss;
  options.loss_scale = FLAGS_loss_scale;
  options.redescending_scale = FLAGS_redescending_scale;
  options.quiet = FLAGS_quiet;
  options.timing = FLAGS_timing;
  options.scan_topic = FLAGS_scan_topic;
  options.joint_state_topic = FLAGS_joint_state_topic;
  options.odom_topic = FLAGS_odom_topic;
  options.left_wheel_joint = FLAGS_left_wheel_joint;
  options.right_wheel_joint = FLAGS_right_wheel_joint;
  options.base_frame = FLAGS_base_frame;
  options.nominal_wheel_radius = FLAGS_nominal_wheel_radius;
  options.nominal_wheelbase = FLAGS_nominal_wheelbase;
  options.lidar_rotation_period_s = FLAGS_lidar_rotation_period;
  options.lidar_beam_timing = FLAGS_lidar_beam_timing;
  options.lidar_self_returns = FLAGS_lidar_self_returns;
  options.lidar_min_range_m = FLAGS_lidar_min_range;
  options.encoder_topic = FLAGS_encoder_topic;
  options.left_encoder_field = FLAGS_left_encoder_field;
  options.right_encoder_field = FLAGS_right_encoder_field;
  options.scan_points = FLAGS_scan_points;
  options.wheel_angle_unit = FLAGS_wheel_angle_unit;
  options.ticks_per_rev = FLAGS_ticks_per_rev;
  options.export_formats = FLAGS_export;
  if (!gflags::GetCommandLineFlagInfoOrDie("time_offset").is_default) {
    options.time_offset_s = FLAGS_time_offset;
  }
  options.plots_dir = FLAGS_plots_dir;
  options.plot_format = FLAGS_plot_format;
  return options;
}

DiagnoseOptions DiagnoseOptionsFromFlags() {
  DiagnoseOptions options;
  static_cast<CalibrateOptions&>(options) = CalibrateOptionsFromFlags();
  options.family_alpha = FLAGS_family_alpha;
  options.max_effects = FLAGS_max_effects;
  options.cv_blocks = FLAGS_cv_blocks;
  options.candidates = FLAGS_candidates;
  options.boundary_speeds = FLAGS_boundary_speeds;
  return options;
}

SimulateOptions SimulateOptionsFromFlags() {
  SimulateOptions options;
  options.output = FLAGS_output;
  options.truth = FLAGS_truth;
  options.intervals = FLAGS_intervals;
  options.seed = FLAGS_seed;
  options.trajectory = FLAGS_trajectory;
  options.noise_xy = FLAGS_noise_xy;
  options.noise_theta = FLAGS_noise_theta;
  options.outliers = FLAGS_outliers;
  options.speed_time_constant = FLAGS_speed_time_constant;
  options.segment_mean = FLAGS_segment_mean;
  options.max_wheel_speed = FLAGS_max_wheel_speed;
  options.time_offset = FLAGS_time_offset;
  options.lateral_slip = FLAGS_lateral_slip;
  options.longitudinal_slip = FLAGS_longitudinal_slip;
  options.radius_change_time = FLAGS_radius_change_time;
  options.r_l_after = FLAGS_r_l_after;
  options.r_r_after = FLAGS_r_r_after;
  options.format = FLAGS_format;
  options.mean_interval = FLAGS_mean_interval;
  options.interval_jitter = FLAGS_interval_jitter;
  options.sensor_period = FLAGS_sensor_period;
  options.sensor_phase = FLAGS_sensor_phase;
  options.sensor_drift = FLAGS_sensor_drift;
  options.logger_period = FLAGS_logger_period;
  options.logger_jitter = FLAGS_logger_jitter;
  options.pickup_latency = FLAGS_pickup_latency;
  options.encoder_period = FLAGS_encoder_period;
  options.encoder_poll_jitter = FLAGS_encoder_poll_jitter;
  options.encoder_stamp_jitter = FLAGS_encoder_stamp_jitter;
  options.repeat_fraction = FLAGS_repeat_fraction;
  options.beams = FLAGS_beams;
  options.field_of_view_deg = FLAGS_field_of_view;
  options.range_noise = FLAGS_range_noise;
  options.missing_returns = FLAGS_missing_returns;
  options.sweep = FLAGS_sweep;
  options.world = FLAGS_world;
  options.upside_down = FLAGS_upside_down;
  options.self_returns = FLAGS_self_returns;
  for (const char* name : {"max_wheel_speed", "mean_interval", "interval_jitter", "segment_mean",
                           "speed_time_constant"}) {
    if (!gflags::GetCommandLineFlagInfoOrDie(name).is_default) options.given.insert(name);
  }
  return options;
}

}  // namespace calib::cli
