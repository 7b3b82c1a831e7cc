#include <calib/core/bearing/bearing_log_io.h>
#include <calib/tools/commands/command_util.h>
#include <calib/tools/report/bearing_report.h>
#include <calib/tools/report/json_output.h>
#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace calib::cli {

int Fail(const std::string& message) {
  std::fprintf(stderr, "calib: error: %s\n", message.c_str());
  return 1;
}

std::function<void(const std::string&)> ProgressPrinter(const Stopwatch& clock, bool quiet,
                                                        std::FILE* out, double after_s) {
  return [clock, quiet, out, after_s](const std::string& line) {
    const double seconds = clock.Seconds();
    if (!quiet && seconds > after_s)
      std::fprintf(out, "calib: %.1f s: %s\n", seconds, line.c_str());
  };
}

Status CheckInput(const std::string& input) {
  if (input.empty()) return Status::InvalidInput("--input is required");
  return Status::Ok();
}

Status CheckOutputPath(const std::string& flag, const std::string& path, bool directory_output) {
  if (path.empty() || path == "-") return Status::Ok();
  const std::filesystem::path file(path);
  const std::filesystem::path folder =
      file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  std::error_code error;
  if (!std::filesystem::is_directory(folder, error)) {
    return Status::Io("--" + flag + " " + path + ": cannot write there, the folder " +
                      folder.string() + " does not exist");
  }
  if (!directory_output && std::filesystem::is_directory(file, error)) {
    return Status::Io("--" + flag + " " + path + ": is a folder, not a file");
  }
  return Status::Ok();
}

bool IsBearingInput(const std::string& input, const std::string& format) {
  return format == "auto" && IsBearingLogDirectory(input);
}

Status CheckTimingFlag(const std::string& timing) {
  if (timing != "auto" && timing != "stamps" && timing != "free_running" && timing != "off") {
    return Status::InvalidInput("--timing " + timing +
                                ": expected auto, stamps, free_running or off");
  }
  return Status::Ok();
}

StatusOr<double> ParseWheelAngleUnit(const std::string& unit) {
  if (unit == "rad") return 1.0;
  if (unit == "deg") return M_PI / 180.0;
  if (unit.rfind("ticks:", 0) == 0) {
    char* end = nullptr;
    const double counts = std::strtod(unit.c_str() + 6, &end);
    if (end != unit.c_str() + 6 && *end == '\0' && counts > 0.0 && std::isfinite(counts)) {
      return 2.0 * M_PI / counts;
    }
  }
  return Status::InvalidInput("--wheel_angle_unit " + unit +
                              ": expected rad, deg or ticks:N (N > 0 counts per wheel turn)");
}

StatusOr<RobustLoss> ParseLossFlags(const std::string& loss, double loss_scale) {
  CALIB_ASSIGN_OR_RETURN(const RobustLoss parsed, ParseRobustLoss(loss));
  if (!(loss_scale > 0.0)) return Status::InvalidInput("--loss_scale must be positive");
  return parsed;
}

StatusOr<LaserLog> ReadLaserInput(const std::string& path, LaserFormat format,
                                  const std::optional<double>& time_offset_s) {
  CALIB_ASSIGN_OR_RETURN(LaserLog log, ReadLaserLog(path, format));
  if (!time_offset_s) return log;
  return ShiftSensorStamps(std::move(log), *time_offset_s);
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

std::string DefaultPlotsDir(const std::string& output) {
  const std::filesystem::path path(output);
  // A device or a pipe (/dev/stdout, /dev/full) has no folder of its own to put plots beside.
  std::error_code error;
  if (std::filesystem::exists(path, error) && !std::filesystem::is_regular_file(path, error)) {
    return "";
  }
  return (path.parent_path() / (path.stem().string() + "_plots")).string();
}

StatusOr<BearingInput> ReadBearingInput(const CalibrateOptions& flags) {
  // Ceres warns on stderr when a covariance is rank deficient; the commands say why themselves.
  FLAGS_minloglevel = std::max(FLAGS_minloglevel, 2);
  BearingInput input;
  CALIB_ASSIGN_OR_RETURN(input.calibration.adjustment.loss,
                         ParseLossFlags(flags.loss, flags.loss_scale));
  input.calibration.adjustment.loss_scale = flags.loss_scale;
  if (!(flags.redescending_scale >= 0.0) || !std::isfinite(flags.redescending_scale)) {
    return Status::InvalidInput("--redescending_scale must be 0 (off) or a positive number");
  }
  input.calibration.adjustment.redescending_scale = flags.redescending_scale;
  input.calibration.adjustment.num_threads = 2;
  CALIB_ASSIGN_OR_RETURN(input.log, ReadBearingLog(flags.input));
  if (flags.time_offset_s) {
    if (!std::isfinite(*flags.time_offset_s)) {
      return Status::InvalidInput("--time_offset is not finite");
    }
    for (BearingRun& run : input.log.runs) {
      for (BearingSample& bearing : run.bearings) bearing.t_s += *flags.time_offset_s;
    }
  }
  return input;
}

int WriteReport(const std::string& output, const nlohmann::ordered_json& json,
                const std::string& summary, bool quiet) {
  if (output == "-") {
    // The JSON owns stdout; the summary goes to stderr so that a pipe reads pure JSON.
    const std::string text = json.dump(2) + "\n";
    if (std::fputs(text.c_str(), stdout) < 0 || std::fflush(stdout) != 0) {
      return Fail("cannot write the JSON on stdout");
    }
    if (!quiet) std::fputs(summary.c_str(), stderr);
    return 0;
  }
  if (!output.empty()) {
    const Status written = WriteJsonFile(output, json);
    if (!written.ok()) return Fail(written.message());
  }
  if (!quiet) std::fputs(summary.c_str(), stdout);
  return 0;
}

}  // namespace calib::cli
