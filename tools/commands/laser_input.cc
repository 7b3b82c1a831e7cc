#include <calib/core/laser/wheel_readings.h>
#include <calib/core/text_number.h>
#include <calib/solvers/laser/laser_input_checks.h>
#include <calib/tools/commands/command_util.h>
#include <calib/tools/commands/laser_input.h>

#include <cmath>
#include <utility>

namespace calib::cli {

StatusOr<std::vector<LaserLog>> ReadCheckedLaserLogs(const CalibrateOptions& flags,
                                                     LaserFormat format) {
  CALIB_ASSIGN_OR_RETURN(std::vector<LaserLog> logs, ReadLaserLogs(flags, format));
  CALIB_RETURN_IF_ERROR(WithWheelUnitHint(CheckLaserLogs(logs), flags));
  return logs;
}

StatusOr<std::vector<LaserLog>> ReadLaserLogs(const CalibrateOptions& flags, LaserFormat format) {
  // --wheel_angle_unit or --ticks_per_rev: the same unit for every log, bag or not.
  CALIB_ASSIGN_OR_RETURN(const double radians_per_unit, WheelRadiansPerUnit(flags));
  std::vector<LaserLog> logs;
  for (const std::string& path : SplitCommas(flags.input)) {
    CALIB_ASSIGN_OR_RETURN(LaserLog log, ReadLaserInput(path, format, flags.time_offset_s));
    if (radians_per_unit != 1.0) {
      CALIB_RETURN_IF_ERROR(ScaleWheelReadings(radians_per_unit, &log));
    }
    logs.push_back(std::move(log));
  }
  if (logs.empty()) return Status::InvalidInput("--input names no file");
  return logs;
}

Status CheckLaserLogs(const std::vector<LaserLog>& logs,
                      std::shared_ptr<const ConsensusScreen>* consensus_screen) {
  LaserInputCheckOptions options;
  if (logs.size() == 1) options.consensus_screen = consensus_screen;
  for (const LaserLog& log : logs) CALIB_RETURN_IF_ERROR(CheckLaserInput(log, options));
  return Status::Ok();
}

Status WithWheelUnitHint(const Status& checked, const CalibrateOptions& flags) {
  if (checked.ok() || (flags.wheel_angle_unit == "rad" && flags.ticks_per_rev == 0.0)) {
    return checked;
  }
  const std::string unit = flags.ticks_per_rev != 0.0
                               ? "--ticks_per_rev " + Num(flags.ticks_per_rev)
                               : "--wheel_angle_unit " + flags.wheel_angle_unit;
  return Status(checked.code(), checked.message() + " (the wheel readings were converted with " +
                                    unit + ": if they are in radians already, leave it out)");
}

StatusOr<double> WheelRadiansPerUnit(const CalibrateOptions& flags) {
  CALIB_ASSIGN_OR_RETURN(const double per_unit, ParseWheelAngleUnit(flags.wheel_angle_unit));
  if (flags.ticks_per_rev == 0.0) return per_unit;
  if (!(flags.ticks_per_rev > 0.0 && std::isfinite(flags.ticks_per_rev))) {
    return Status::InvalidInput("--ticks_per_rev must be positive (ticks per wheel turn)");
  }
  if (flags.wheel_angle_unit != "rad") {
    return Status::InvalidInput("--ticks_per_rev and --wheel_angle_unit " + flags.wheel_angle_unit +
                                " both give the wheel angles' unit: "
                                "give one");
  }
  return 2.0 * M_PI / flags.ticks_per_rev;
}

}  // namespace calib::cli
