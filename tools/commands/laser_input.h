#ifndef CALIB_TOOLS_COMMANDS_LASER_INPUT_H_
#define CALIB_TOOLS_COMMANDS_LASER_INPUT_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/status.h>
#include <calib/solvers/laser/censi_consensus.h>
#include <calib/tools/commands/commands.h>

#include <memory>
#include <string>
#include <vector>

// The laser logs of --input as calibrate and diagnose take them: read, the wheel readings
// converted to radians (--wheel_angle_unit, --ticks_per_rev), and checked for the common input
// mistakes (solvers/laser/laser_input_checks.h).
namespace calib::cli {

StatusOr<std::vector<LaserLog>> ReadCheckedLaserLogs(const CalibrateOptions& flags,
                                                     LaserFormat format);
// The two halves: read and converted, then checked (calibrate starts its model screen between
// them, so that the screen's thread runs beside the checks too).
StatusOr<std::vector<LaserLog>> ReadLaserLogs(const CalibrateOptions& flags, LaserFormat format);
// `consensus_screen`, when not null, receives a single log's consensus screen for the
// calibration to reuse (LaserInputCheckOptions::consensus_screen).
Status CheckLaserLogs(const std::vector<LaserLog>& logs,
                      std::shared_ptr<const ConsensusScreen>* consensus_screen = nullptr);

// A failed input check with, when the flags gave the wheel readings a unit, a word that the unit
// may be the mistake (a wrong unit scales the radii just as a file in another unit does).
Status WithWheelUnitHint(const Status& checked, const CalibrateOptions& flags);

// --ticks_per_rev for a bag: the JointState positions' radians per unit, as --wheel_angle_unit
// ticks:N; an error when both flags give a unit.
StatusOr<double> WheelRadiansPerUnit(const CalibrateOptions& flags);

}  // namespace calib::cli

#endif  // CALIB_TOOLS_COMMANDS_LASER_INPUT_H_
