#ifndef CALIB_TOOLS_COMMANDS_COMMAND_UTIL_H_
#define CALIB_TOOLS_COMMANDS_COMMAND_UTIL_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/status.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <calib/solvers/common/robust_loss.h>
#include <calib/tools/commands/commands.h>

#include <chrono>
#include <cstdio>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

// What every command does the same way: fail, time, report progress, check the loss flags,
// write the report.
namespace calib::cli {

// Prints "calib: error: MESSAGE" on stderr; returns the exit status 1.
int Fail(const std::string& message);

class Stopwatch {
 public:
  double Seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

// A progress callback for the library's options: prints "calib: 1.3 s: LINE" on `out` once the
// run has taken longer than `after_s` (short runs stay silent), and nothing when `quiet`.
std::function<void(const std::string&)> ProgressPrinter(const Stopwatch& clock, bool quiet,
                                                        std::FILE* out = stderr,
                                                        double after_s = 1.0);

// The check every command on a log starts with: --input given (--output is optional).
Status CheckInput(const std::string& input);

// An output path (not empty, not "-") must be in a folder that exists, and not be a folder
// itself unless `directory_output`: checked before any work, the path named.
Status CheckOutputPath(const std::string& flag, const std::string& path,
                       bool directory_output = false);

// True when --format is auto and --input is a bearing log directory.
bool IsBearingInput(const std::string& input, const std::string& format);

// The robust loss named by --loss, with --loss_scale checked positive.
StatusOr<RobustLoss> ParseLossFlags(const std::string& loss, double loss_scale);

// --timing: auto, stamps, free_running or off.
Status CheckTimingFlag(const std::string& timing);

// --wheel_angle_unit: rad, deg or ticks:N (N counts per wheel turn), as radians per unit.
StatusOr<double> ParseWheelAngleUnit(const std::string& unit);

// The value named `name` among `choices`, or "unknown --FLAG 'NAME' (EXPECTED)".
template <typename Enum>
StatusOr<Enum> ParseChoice(const std::string& flag, const std::string& name,
                           const std::vector<std::pair<std::string, Enum>>& choices,
                           const std::string& expected) {
  for (const auto& [choice, value] : choices) {
    if (choice == name) return value;
  }
  return Status::InvalidInput("unknown --" + flag + " '" + name + "' (" + expected + ")");
}

// What both bearing commands start with: Ceres' warnings silenced, the loss flags checked, the
// log read, and the calibration options from the flags (loss, two threads; no progress).
struct BearingInput {
  BearingLog log;
  BearingCalibrationOptions calibration;
};
StatusOr<BearingInput> ReadBearingInput(const CalibrateOptions& flags);

// ReadLaserLog, with --time_offset applied to the sensor's stamps when given.
StatusOr<LaserLog> ReadLaserInput(const std::string& path, LaserFormat format,
                                  const std::optional<double>& time_offset_s);

// "a.json,b.json" → {"a.json", "b.json"} (empty parts dropped).
std::vector<std::string> SplitCommas(const std::string& text);

// The default plot folder: OUT_plots beside OUT.json; none ("") when OUT is not a regular file
// (a device or a pipe).
std::string DefaultPlotsDir(const std::string& output);

// The end of every command: writes `json` to `output`, then prints `summary` on stdout unless
// `quiet`. Returns the exit status.
int WriteReport(const std::string& output, const nlohmann::ordered_json& json,
                const std::string& summary, bool quiet);

}  // namespace calib::cli

#endif  // CALIB_TOOLS_COMMANDS_COMMAND_UTIL_H_
