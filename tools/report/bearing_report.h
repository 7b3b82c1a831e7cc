#ifndef CALIB_TOOLS_REPORT_BEARING_REPORT_H_
#define CALIB_TOOLS_REPORT_BEARING_REPORT_H_

#include <calib/solvers/bearing/calibrate_bearing.h>
#include <calib/tools/report/stream_timing_report.h>

#include <nlohmann/json.hpp>
#include <string>

namespace calib {

// True for a directory that looks like a bearing log (CONTRACT.md): it holds bearings.csv or
// meta.json (a laser stream directory holds odometry.csv and sensor_poses.csv only).
bool IsBearingLogDirectory(const std::string& path);

// {PARAM: value} with the contract's names: the observable set, then ρ, δR, δL, δB when `metric`
// is given.
nlohmann::ordered_json BearingParamObject(const BearingParamVector& v,
                                          const BearingMetricVector* metric);

// The contract's OUT.json for the bearing problem (SI units, radians), with the detail a user
// needs to check the result: covariance, noise levels, per-run fit, timings.
// With stream timing also "timing": {"streams": [...]} (StreamTimingJson).
nlohmann::ordered_json BearingResultJson(const BearingCalibrationResult& result,
                                         const std::string& input, const std::string& loss,
                                         const std::vector<StreamTiming>& stream_timing = {});

// The short human-readable summary printed on stdout (degrees for the angles).
std::string BearingResultSummary(const BearingCalibrationResult& result, const std::string& input,
                                 const std::string& loss,
                                 const std::vector<StreamTiming>& stream_timing = {});

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_BEARING_REPORT_H_
