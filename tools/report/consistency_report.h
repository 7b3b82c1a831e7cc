#ifndef CALIB_TOOLS_REPORT_CONSISTENCY_REPORT_H_
#define CALIB_TOOLS_REPORT_CONSISTENCY_REPORT_H_

#include <calib/solvers/laser/laser_consistency.h>

#include <nlohmann/json.hpp>
#include <string>

namespace calib {

// The "consistency" object of the laser JSON: every window with its predicted and measured
// totals, their σ's, z and p (SI units: rad, m), the family and its lags, and the warnings.
nlohmann::ordered_json LaserConsistencyJson(const LaserConsistency& consistency);

// Summary lines (degrees, m): the whole runs' totals side by side and how many windows disagree.
std::string LaserConsistencySummary(const LaserConsistency& consistency);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_CONSISTENCY_REPORT_H_
