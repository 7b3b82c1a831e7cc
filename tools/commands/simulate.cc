// `calib simulate`: writes a simulated laser log and, with --truth, the truth it was made from.
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/core/text_number.h>
#include <calib/core/timing/logging_model.h>
#include <calib/tools/commands/command_util.h>
#include <calib/tools/commands/commands.h>
#include <calib/tools/commands/simulate_scans.h>
#include <calib/tools/report/json_output.h>
#include <calib/tools/report/laser_report.h>
#include <calib/tools/report/stream_timing_report.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <tuple>

namespace calib::cli {
namespace {

StatusOr<LaserTrajectory> ParseTrajectory(const std::string& name) {
  return ParseChoice<LaserTrajectory>("trajectory", name,
                                      {{"rich", LaserTrajectory::kRich},
                                       {"straight", LaserTrajectory::kStraight},
                                       {"rotation", LaserTrajectory::kPureRotation},
                                       {"arc", LaserTrajectory::kConstantArc}},
                                      "rich, straight, rotation, arc");
}

StatusOr<LaserSimOptions> SimulatorOptions(const SimulateOptions& flags) {
  LaserSimOptions options;
  options.num_intervals = flags.intervals;
  options.seed = flags.seed;
  CALIB_ASSIGN_OR_RETURN(options.trajectory, ParseTrajectory(flags.trajectory));
  if (flags.intervals <= 0) return Status::InvalidInput("--intervals must be positive");
  options.scan_noise_sigma = Eigen::Vector3d(flags.noise_xy, flags.noise_xy, flags.noise_theta);
  options.outlier_fraction = flags.outliers;
  options.speed_time_constant_s = flags.speed_time_constant;
  options.segment_mean_s = flags.segment_mean;
  options.max_wheel_speed = flags.max_wheel_speed;
  if (flags.speed_time_constant < 0.0 || !(flags.segment_mean > 0.0) ||
      !(flags.max_wheel_speed > 0.0)) {
    return Status::InvalidInput(
        "--speed_time_constant must be >= 0, --segment_mean and --max_wheel_speed > 0");
  }
  options.effects.time_offset_s = flags.time_offset;
  options.effects.lateral_slip_s = flags.lateral_slip;
  options.effects.longitudinal_slip_s = flags.longitudinal_slip;
  options.effects.radius_change_time_s = flags.radius_change_time;
  options.effects.left_radius_after_m = flags.r_l_after;
  options.effects.right_radius_after_m = flags.r_r_after;
  if (!(flags.mean_interval > 0.0) || !(flags.interval_jitter >= 0.0) ||
      !std::isfinite(flags.mean_interval) || !std::isfinite(flags.interval_jitter)) {
    return Status::InvalidInput("--mean_interval must be > 0 and --interval_jitter >= 0, got " +
                                Num(flags.mean_interval) + " and " + Num(flags.interval_jitter));
  }
  options.mean_interval_s = flags.mean_interval;
  options.interval_jitter_s = flags.interval_jitter;
  return options;
}

// The flags of the logging model, by name, for the messages and the truth.
std::vector<std::pair<const char*, double>> LoggingFlags(const SimulateOptions& flags) {
  return {{"sensor_period", flags.sensor_period},
          {"sensor_phase", flags.sensor_phase},
          {"sensor_drift", flags.sensor_drift},
          {"logger_period", flags.logger_period},
          {"logger_jitter", flags.logger_jitter},
          {"pickup_latency", flags.pickup_latency},
          {"encoder_period", flags.encoder_period},
          {"encoder_poll_jitter", flags.encoder_poll_jitter},
          {"encoder_stamp_jitter", flags.encoder_stamp_jitter},
          {"repeat_fraction", flags.repeat_fraction}};
}

StatusOr<LoggingModel> LoggingModelFromFlags(const SimulateOptions& flags) {
  for (const auto& [name, value] : LoggingFlags(flags)) {
    const bool may_be_negative = std::string(name) == "sensor_drift";
    if (!std::isfinite(value) || (!may_be_negative && value < 0.0)) {
      return Status::InvalidInput(std::string("--") + name + " must be a finite number" +
                                  (may_be_negative ? "" : " >= 0") + ", got " + Num(value));
    }
  }
  LoggingModel model;
  model.sensor_period_s = flags.sensor_period;
  model.sensor_phase_s = flags.sensor_phase;
  model.sensor_clock_drift = flags.sensor_drift;
  model.logger_period_s = flags.logger_period;
  model.logger_jitter_s = flags.logger_jitter;
  model.pickup_latency_s = flags.pickup_latency;
  model.encoder_period_s = flags.encoder_period;
  model.encoder_poll_jitter_s = flags.encoder_poll_jitter;
  model.encoder_stamp_jitter_s = flags.encoder_stamp_jitter;
  model.repeat_fraction = flags.repeat_fraction;
  // The library's message names the field: --NAME sets NAME_s (--sensor_drift:
  // sensor_clock_drift).
  const Status valid = ValidateLoggingModel(model);
  if (!valid.ok()) {
    return Status::InvalidInput("bad logging flags (--NAME sets the field NAME_s): " +
                                valid.message());
  }
  return model;
}

// The truth, and the settings that made it.
nlohmann::ordered_json TruthJson(const LaserSimTruth& truth, const SimulateOptions& flags) {
  nlohmann::ordered_json json = LaserSimTruthJson(truth);
  json["simulation"] = {{"intervals", flags.intervals},
                        {"seed", flags.seed},
                        {"trajectory", flags.trajectory},
                        {"noise_xy", flags.noise_xy},
                        {"noise_theta", flags.noise_theta},
                        {"outliers", flags.outliers},
                        {"speed_time_constant", flags.speed_time_constant},
                        {"segment_mean", flags.segment_mean},
                        {"max_wheel_speed", flags.max_wheel_speed},
                        {"mean_interval", flags.mean_interval},
                        {"interval_jitter", flags.interval_jitter}};
  return json;
}

// The logging model's flags and, per written row, the true time of its sample.
void AddTimingTruth(const SimulateOptions& flags, const LoggedTimingTruth& timing,
                    nlohmann::ordered_json* json) {
  nlohmann::ordered_json logging;
  for (const auto& [name, value] : LoggingFlags(flags)) logging[name] = value;
  (*json)["logging"] = logging;
  (*json)["timing"] = LoggedTimingTruthJson(timing);
}

bool EndsWith(const std::string& text, const std::string& suffix) {
  return text.size() > suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// --format auto: .csv → CSV, no extension → raw streams, anything else → tuples.
StatusOr<LaserFormat> OutputFormat(const SimulateOptions& flags) {
  CALIB_ASSIGN_OR_RETURN(const LaserFormat format, ParseLaserFormat(flags.format));
  if (format != LaserFormat::kAuto) return format;
  if (EndsWith(flags.output, ".csv")) return LaserFormat::kCsv;
  const std::filesystem::path path(flags.output);
  const bool no_extension = path.has_filename() ? !path.filename().has_extension() : true;
  return no_extension ? LaserFormat::kStream : LaserFormat::kTuples;
}

int WriteTruth(const SimulateOptions& flags, const nlohmann::ordered_json& json) {
  if (flags.truth.empty()) return 0;
  const Status written = WriteJsonFile(flags.truth, json);
  return written.ok() ? 0 : Fail(written.message());
}

}  // namespace

int RunSimulate(const SimulateOptions& flags) {
  if (flags.output.empty()) return Fail("--output is required");
  for (const auto& [flag, path, folder] :
       {std::tuple<std::string, std::string, bool>{"output", flags.output, true},
        {"truth", flags.truth, false}}) {
    const Status checked = CheckOutputPath(flag, path, folder);
    if (!checked.ok()) return Fail(checked.message());
  }
  const StatusOr<LaserSimOptions> options = SimulatorOptions(flags);
  if (!options.ok()) return Fail(options.message());
  const StatusOr<LoggingModel> model = LoggingModelFromFlags(flags);
  if (!model.ok()) return Fail(model.message());
  if (flags.beams > 0) return SimulateScanRobot(flags, *options, *model);
  const StatusOr<LaserFormat> format = OutputFormat(flags);
  if (!format.ok()) return Fail(format.message());
  LaserSimTruth truth;
  if (*format == LaserFormat::kStream) {
    LoggedTimingTruth timing;
    const LaserStreams streams = SimulateLoggedLaserStreams(*options, *model, &truth, &timing);
    const Status written = WriteLaserStream(streams.odometry, streams.sensor_poses, flags.output);
    if (!written.ok()) return Fail(written.message());
    nlohmann::ordered_json json = TruthJson(truth, flags);
    AddTimingTruth(flags, timing, &json);
    return WriteTruth(flags, json);
  }
  if (!model->IsClean()) {
    return Fail(
        "the logging flags (--sensor_period, --logger_period, --encoder_period, ...) need a raw "
        "stream output: --format stream, or an --output without extension (got " +
        flags.output + ")");
  }
  const LaserLog log = SimulateLaserLog(*options, &truth);
  const Status written = *format == LaserFormat::kCsv ? WriteLaserCsv(log, flags.output)
                                                      : WriteLaserTuples(log, flags.output);
  if (!written.ok()) return Fail(written.message());
  return WriteTruth(flags, TruthJson(truth, flags));
}

}  // namespace calib::cli
