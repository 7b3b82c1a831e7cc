#ifndef CALIB_TOOLS_COMMANDS_LASER_INPUT_H_
#define CALIB_TOOLS_COMMANDS_LASER_INPUT_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/status.h>
#include <calib/tools/commands/commands.h>

#include <string>
#include <vector>

// The laser logs of --input as calibrate and diagnose take them: read, the wheel readings
// converted from ticks (--ticks_per_rev), and checked for the common input mistakes
// (solvers/laser/laser_input_checks.h).
namespace calib::cli {

StatusOr<std::vector<LaserLog>> ReadCheckedLaserLogs(const CalibrateOptions& flags,
                                                     LaserFormat format);
// The two halves: read and converted, then checked (calibrate starts its model screen between
// them, so that the screen's thread runs beside the checks too).
StatusOr<std::vector<LaserLog>> ReadLaserLogs(const CalibrateOptions& flags, LaserFormat format);
Status CheckLaserLogs(const std::vector<LaserLog>& logs);

// --ticks_per_rev for a bag: the JointState positions' radians per unit, as --wheel_angle_unit
// ticks:N; an error when both flags give a unit.
StatusOr<double> WheelRadiansPerUnit(const CalibrateOptions& flags);

}  // namespace calib::cli

#endif  // CALIB_TOOLS_COMMANDS_LASER_INPUT_H_
