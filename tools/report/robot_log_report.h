#ifndef CALIB_TOOLS_REPORT_ROBOT_LOG_REPORT_H_
#define CALIB_TOOLS_REPORT_ROBOT_LOG_REPORT_H_

#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/scan_matching/robot_bag_log.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

// What calib made of a robot's recording (a bag), in the calibrate JSON ("recording": {...}) and
// the summary: the topics read, where the wheel angles came from, the scan matching, and the
// calibration against the nominal values (tf's mounting; the driver's wheels when the wheel
// angles came from its odometry).
namespace calib {

struct NominalWheels {  // The driver's values, when given (0: not given).
  double wheel_radius_m = 0.0, wheelbase_m = 0.0;
};

nlohmann::ordered_json RobotLogJson(const RobotBagLog& log, const LaserCalibrationResult& result,
                                    const NominalWheels& nominal);

std::string RobotLogSummary(const RobotBagLog& log, const LaserCalibrationResult& result,
                            const NominalWheels& nominal);

// The refinement on the scan points ("scan_points": {...}): its estimate and σ, the two-stage
// estimate it started from and how far it moved (in the two-stage σ), its pairs and lines; or
// why it failed.
nlohmann::ordered_json ScanPointJson(const RobotBagCalibration& bag);
std::string ScanPointSummary(const RobotBagCalibration& bag);
// Its warnings and failure, for the verdict.
std::vector<std::string> ScanPointWarnings(const RobotBagCalibration& bag);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_ROBOT_LOG_REPORT_H_
