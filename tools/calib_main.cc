// calib: offline calibration of a differential-drive robot from its own logs.
//   calib calibrate --input PATH --output OUT.json [--format ...] [--loss ...]
#include <gflags/gflags.h>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/tools/report/bearing_report.h>
#include <calib/tools/report/laser_diagnose_report.h>
#include <calib/tools/report/laser_report.h>

DEFINE_string(input, "",
              "A laser log file (tuples or CSV), a laser raw-stream directory, several laser logs "
              "separated by commas (calibrated jointly), or a bearing log directory "
              "(odometry.csv, bearings.csv, meta.json)");
DEFINE_string(output, "", "Where to write the JSON result");
DEFINE_string(format, "auto", "Laser log format: auto, tuples, csv or stream");
DEFINE_string(loss, "cauchy", "Robust loss: cauchy, huber or none");
DEFINE_double(loss_scale, 3.0, "Scale of the robust loss, in whitened residual units");
DEFINE_bool(quiet, false, "Do not print the summary on stdout");

// `calib simulate`: a laser log with known truth.
DEFINE_string(truth, "", "simulate: where to write the truth as JSON (optional)");
DEFINE_int32(intervals, 2000, "simulate: number of intervals");
DEFINE_uint64(seed, 1, "simulate: random seed");
DEFINE_string(trajectory, "rich", "simulate: rich, straight, rotation or arc");
DEFINE_double(noise_xy, 0.001, "simulate: scan-matching noise sigma on x and y (m)");
DEFINE_double(noise_theta, 0.002, "simulate: scan-matching noise sigma on theta (rad)");
DEFINE_double(outliers, 0.0, "simulate: fraction of slip outliers");
DEFINE_double(speed_time_constant, 0.5,
              "simulate: wheel speeds follow their targets with this lag (s); 0: speeds constant "
              "within each interval");
DEFINE_double(segment_mean, 6.0, "simulate: mean time between new speed targets (s)");
DEFINE_double(max_wheel_speed, 0.5, "simulate: largest commanded wheel speed (rad/s)");
DEFINE_double(time_offset, 0.0, "simulate: scans stamped t were taken at t + this (s)");
DEFINE_double(lateral_slip, 0.0, "simulate: lateral velocity = this * v * omega (s)");
DEFINE_double(longitudinal_slip, 0.0, "simulate: forward velocity = v - this * dv/dt (s)");
DEFINE_double(radius_change_time, -1.0, "simulate: time of a wheel-radius change (s), < 0: none");
DEFINE_double(r_l_after, 0.0, "simulate: left radius after the change (m)");
DEFINE_double(r_r_after, 0.0, "simulate: right radius after the change (m)");

namespace {

constexpr char kUsage[] =
    "calib <command> [flags]\n"
    "  calibrate --input PATH --output OUT.json   estimate the calibration\n"
    "  diagnose  --input PATH --output OUT.json   find physics the model leaves out\n"
    "  simulate  --output LOG [--truth T.json]    write a simulated laser log (.tuple or .csv)\n";

int Fail(const std::string& message) {
  std::fprintf(stderr, "calib: error: %s\n", message.c_str());
  return 1;
}

std::vector<std::string> SplitCommas(const std::string& text) {
  std::vector<std::string> parts;
  std::stringstream stream(text);
  std::string part;
  while (std::getline(stream, part, ',')) {
    if (!part.empty()) parts.push_back(part);
  }
  return parts;
}

int Calibrate() {
  if (FLAGS_input.empty()) return Fail("--input is required");
  if (FLAGS_output.empty()) return Fail("--output is required");
  if (FLAGS_format == "auto" && calib::IsBearingLogDirectory(FLAGS_input)) {
    return calib::CalibrateBearingCommand(FLAGS_input, FLAGS_output, FLAGS_loss, FLAGS_loss_scale,
                                          FLAGS_quiet);
  }
  const calib::StatusOr<calib::LaserFormat> format = calib::ParseLaserFormat(FLAGS_format);
  if (!format.ok()) return Fail(format.message());
  const calib::StatusOr<calib::RobustLoss> loss = calib::ParseRobustLoss(FLAGS_loss);
  if (!loss.ok()) return Fail(loss.message());
  if (!(FLAGS_loss_scale > 0.0)) return Fail("--loss_scale must be positive");

  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&]() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  std::vector<calib::LaserLog> logs;
  for (const std::string& path : SplitCommas(FLAGS_input)) {
    calib::StatusOr<calib::LaserLog> log = calib::ReadLaserLog(path, *format);
    if (!log.ok()) return Fail(log.message());
    logs.push_back(std::move(log).value());
  }
  if (logs.empty()) return Fail("--input names no file");
  std::vector<const std::vector<calib::LaserInterval>*> intervals;
  for (const calib::LaserLog& log : logs) intervals.push_back(&log.intervals);

  calib::LaserCalibrationOptions options;
  options.refinement.loss = *loss;
  options.refinement.loss_scale = FLAGS_loss_scale;
  options.progress = [&](const std::string& line) {
    if (elapsed() > 1.0) std::fprintf(stderr, "calib: %.1f s: %s\n", elapsed(), line.c_str());
  };
  const calib::StatusOr<calib::LaserCalibrationResult> result =
      calib::CalibrateLaserJoint(intervals, options);
  if (!result.ok()) return Fail(FLAGS_input + ": " + result.message());

  nlohmann::ordered_json json = calib::LaserResultJson(*result, FLAGS_input, FLAGS_loss);
  json["seconds"]["total"] = elapsed();
  std::ofstream out(FLAGS_output);
  if (!out) return Fail("cannot write " + FLAGS_output);
  out << json.dump(2) << "\n";
  if (!out) return Fail("cannot write " + FLAGS_output);
  if (!FLAGS_quiet) {
    std::fputs(calib::LaserResultSummary(*result, FLAGS_input, FLAGS_loss).c_str(), stdout);
  }
  return 0;
}

int Simulate() {
  if (FLAGS_output.empty()) return Fail("--output is required");
  calib::LaserSimOptions options;
  options.num_intervals = FLAGS_intervals;
  options.seed = FLAGS_seed;
  if (FLAGS_trajectory == "rich") {
    options.trajectory = calib::LaserTrajectory::kRich;
  } else if (FLAGS_trajectory == "straight") {
    options.trajectory = calib::LaserTrajectory::kStraight;
  } else if (FLAGS_trajectory == "rotation") {
    options.trajectory = calib::LaserTrajectory::kPureRotation;
  } else if (FLAGS_trajectory == "arc") {
    options.trajectory = calib::LaserTrajectory::kConstantArc;
  } else {
    return Fail("unknown --trajectory '" + FLAGS_trajectory + "' (rich, straight, rotation, arc)");
  }
  if (FLAGS_intervals <= 0) return Fail("--intervals must be positive");
  options.scan_noise_sigma = Eigen::Vector3d(FLAGS_noise_xy, FLAGS_noise_xy, FLAGS_noise_theta);
  options.outlier_fraction = FLAGS_outliers;
  options.speed_time_constant_s = FLAGS_speed_time_constant;
  options.segment_mean_s = FLAGS_segment_mean;
  options.max_wheel_speed = FLAGS_max_wheel_speed;
  if (FLAGS_speed_time_constant < 0.0 || !(FLAGS_segment_mean > 0.0) ||
      !(FLAGS_max_wheel_speed > 0.0)) {
    return Fail("--speed_time_constant must be >= 0, --segment_mean and --max_wheel_speed > 0");
  }
  options.effects.time_offset_s = FLAGS_time_offset;
  options.effects.lateral_slip_s = FLAGS_lateral_slip;
  options.effects.longitudinal_slip_s = FLAGS_longitudinal_slip;
  options.effects.radius_change_time_s = FLAGS_radius_change_time;
  options.effects.left_radius_after_m = FLAGS_r_l_after;
  options.effects.right_radius_after_m = FLAGS_r_r_after;
  calib::LaserSimTruth truth;
  const calib::LaserLog log = calib::SimulateLaserLog(options, &truth);
  const bool csv =
      FLAGS_output.size() > 4 && FLAGS_output.substr(FLAGS_output.size() - 4) == ".csv";
  const calib::Status written =
      csv ? calib::WriteLaserCsv(log, FLAGS_output) : calib::WriteLaserTuples(log, FLAGS_output);
  if (!written.ok()) return Fail(written.message());
  if (!FLAGS_truth.empty()) {
    nlohmann::ordered_json json;
    json["problem"] = "laser";
    json["estimate"] = {
        {"r_l", truth.odometry.left_radius_m}, {"r_r", truth.odometry.right_radius_m},
        {"b", truth.odometry.wheelbase_m},     {"sensor_x", truth.base_T_sensor(0)},
        {"sensor_y", truth.base_T_sensor(1)},  {"sensor_theta", truth.base_T_sensor(2)}};
    json["effects"] = {{"time_offset", truth.effects.time_offset_s},
                       {"lateral_slip", truth.effects.lateral_slip_s},
                       {"longitudinal_slip", truth.effects.longitudinal_slip_s},
                       {"wheel_radius_change", truth.effects.radius_change_time_s},
                       {"r_l_after", truth.effects.left_radius_after_m},
                       {"r_r_after", truth.effects.right_radius_after_m}};
    json["simulation"] = {{"intervals", FLAGS_intervals},
                          {"seed", FLAGS_seed},
                          {"trajectory", FLAGS_trajectory},
                          {"noise_xy", FLAGS_noise_xy},
                          {"noise_theta", FLAGS_noise_theta},
                          {"outliers", FLAGS_outliers},
                          {"speed_time_constant", FLAGS_speed_time_constant},
                          {"segment_mean", FLAGS_segment_mean},
                          {"max_wheel_speed", FLAGS_max_wheel_speed}};
    std::ofstream out(FLAGS_truth);
    out << json.dump(2) << "\n";
    if (!out) return Fail("cannot write " + FLAGS_truth);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  gflags::SetUsageMessage(kUsage);
  gflags::ParseCommandLineFlags(&argc, &argv, true);
  if (argc != 2) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  const std::string command = argv[1];
  if (command == "calibrate") return Calibrate();
  if (command == "simulate") return Simulate();
  if (command == "diagnose") return calib::RunDiagnoseCommand();
  std::fprintf(stderr, "calib: unknown command '%s'\n%s", command.c_str(), kUsage);
  return 2;
}
