#ifndef CALIB_TOOLS_REPORT_DRIFT_REPORT_H_
#define CALIB_TOOLS_REPORT_DRIFT_REPORT_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/odometry_drift.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <calib/solvers/laser/calibrate_laser.h>

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

// The odometry drift a calibration leaves (its 1σ) and the drift of the nominal wheels it
// replaces, for the summary and the JSON's "odometry_drift".
namespace calib {

struct DriftReport {
  OdometryDrift calibrated_1sigma;
  std::optional<OdometryDrift> nominal;  // Odometry with the nominal wheels on the calibrated.
};

// `nominal`: the driver's wheels when known (radius, radius, wheelbase).
DriftReport LaserDrift(const LaserCalibrationResult& result,
                       const std::optional<OdometryParams>& nominal);
// Needs the metric set (the radii in metres); empty without it.
std::optional<DriftReport> BearingDrift(const BearingCalibrationResult& result,
                                        const BearingLog& log);

nlohmann::ordered_json DriftJson(const DriftReport& report);
std::string DriftSummary(const DriftReport& report);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_DRIFT_REPORT_H_
