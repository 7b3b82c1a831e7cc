#ifndef CALIB_TOOLS_REPORT_LASER_REPORT_H_
#define CALIB_TOOLS_REPORT_LASER_REPORT_H_

#include <calib/solvers/laser/calibrate_laser.h>

#include <nlohmann/json.hpp>
#include <string>

namespace calib {

// The contract's OUT.json for the laser problem (SI units), with the extra detail a user needs
// to check the result: covariance, noise, observability, timings.
nlohmann::ordered_json LaserResultJson(const LaserCalibrationResult& result,
                                       const std::string& input, const std::string& loss);

// The short human-readable summary printed on stdout (mm and degrees).
std::string LaserResultSummary(const LaserCalibrationResult& result, const std::string& input,
                               const std::string& loss);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_LASER_REPORT_H_
