#ifndef CALIB_TOOLS_REPORT_LASER_REPORT_H_
#define CALIB_TOOLS_REPORT_LASER_REPORT_H_

#include <calib/core/laser/laser_simulator.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/tools/report/stream_timing_report.h>

#include <nlohmann/json.hpp>
#include <string>

namespace calib {

// The contract's OUT.json for the laser problem (SI units), with the extra detail a user needs
// to check the result: covariance, noise, observability, timings; with raw streams also
// "timing": {"streams": [...]} (StreamTimingJson).
nlohmann::ordered_json LaserResultJson(const LaserCalibrationResult& result,
                                       const std::string& input, const std::string& loss,
                                       const std::vector<StreamTiming>& stream_timing = {});

// The six parameters as {"r_l": …, …, "sensor_theta": …}.
nlohmann::ordered_json LaserParamJson(const LaserParamVector& v);

// The truth of a simulated log in the result's layout ({"problem", "estimate"}) plus the
// simulated effects (`calib simulate --truth`).
nlohmann::ordered_json LaserSimTruthJson(const LaserSimTruth& truth);

// The short human-readable summary printed on stdout (mm and degrees).
std::string LaserResultSummary(const LaserCalibrationResult& result, const std::string& input,
                               const std::string& loss,
                               const std::vector<StreamTiming>& stream_timing = {});

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_LASER_REPORT_H_
