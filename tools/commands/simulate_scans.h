#ifndef CALIB_TOOLS_COMMANDS_SIMULATE_SCANS_H_
#define CALIB_TOOLS_COMMANDS_SIMULATE_SCANS_H_

#include <calib/core/laser/laser_simulator.h>
#include <calib/core/timing/logging_model.h>
#include <calib/tools/commands/commands.h>

namespace calib::cli {

// `calib simulate --beams N`: the scan robot's recording, with the motion settings of `laser`
// (intervals, seed, trajectory, effects) and the logging model; returns the exit status.
int SimulateScanRobot(const SimulateOptions& flags, const LaserSimOptions& laser,
                      const LoggingModel& model);

}  // namespace calib::cli

#endif  // CALIB_TOOLS_COMMANDS_SIMULATE_SCANS_H_
