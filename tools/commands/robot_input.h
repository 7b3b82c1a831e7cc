#ifndef CALIB_TOOLS_COMMANDS_ROBOT_INPUT_H_
#define CALIB_TOOLS_COMMANDS_ROBOT_INPUT_H_

#include <calib/core/bag/robot_messages.h>
#include <calib/core/status.h>
#include <calib/solvers/scan_matching/robot_bag_log.h>
#include <calib/tools/commands/commands.h>

#include <string>

// A robot's recording on the command line (a ROS bag, a bag directory, a directory of
// scans.csv and odometry.csv, or a CSM laser log with the wheels' counts: csm_log.h; several
// bags or CSM logs separated by commas as one), read with the options its flags give; shared by
// calibrate and diagnose.
namespace calib::cli {

bool IsRobotInput(const std::string& input);

struct RobotInput {
  RobotMessages bag;
  RobotBagOptions options;  // Topics, joints, frames, nominal wheels, unit, --scan_points.
};

// Fails on --timing off (a bag's scans are timed by the calibration), bad flags, or a bag that
// cannot be read.
StatusOr<RobotInput> ReadRobotInput(const CalibrateOptions& flags);

}  // namespace calib::cli

#endif  // CALIB_TOOLS_COMMANDS_ROBOT_INPUT_H_
