#include <calib/tools/commands/flags.h>
#include <gflags/gflags.h>

// Defaults come from the options structs, so that the flags and the structs cannot disagree.
namespace {
const calib::cli::DiagnoseOptions kDiagnose;
const calib::cli::SimulateOptions kSimulate;
}  // namespace

DEFINE_string(input, "",
              "A laser log file (tuples or CSV), a laser raw-stream directory, several laser logs "
              "separated by commas (calibrated jointly), or a bearing log directory "
              "(odometry.csv, bearings.csv, meta.json)");
DEFINE_string(output, "", "Where to write the JSON result");
DEFINE_string(format, kDiagnose.format.c_str(), "Laser log format: auto, tuples, csv or stream");
DEFINE_string(loss, kDiagnose.loss.c_str(), "Robust loss: cauchy, huber or none");
DEFINE_double(loss_scale, kDiagnose.loss_scale,
              "Scale of the robust loss, in whitened residual units");
DEFINE_bool(quiet, kDiagnose.quiet, "Do not print the summary on stdout");

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
              "diagnose: folder for the SVG plots (default: OUT_plots next to "
              "the JSON output)");

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
              "simulate: scans stamped t were taken at t + this (s)");
DEFINE_double(lateral_slip, kSimulate.lateral_slip,
              "simulate: lateral velocity = this * v * omega (s)");
DEFINE_double(longitudinal_slip, kSimulate.longitudinal_slip,
              "simulate: forward velocity = v - this * dv/dt (s)");
DEFINE_double(radius_change_time, kSimulate.radius_change_time,
              "simulate: time of a wheel-radius change (s), < 0: none");
DEFINE_double(r_l_after, kSimulate.r_l_after, "simulate: left radius after the change (m)");
DEFINE_double(r_r_after, kSimulate.r_r_after, "simulate: right radius after the change (m)");

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
  options.quiet = FLAGS_quiet;
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
  options.plots_dir = FLAGS_plots_dir;
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
  return options;
}

}  // namespace calib::cli
