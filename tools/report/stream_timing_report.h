#ifndef CALIB_TOOLS_REPORT_STREAM_TIMING_REPORT_H_
#define CALIB_TOOLS_REPORT_STREAM_TIMING_REPORT_H_

#include <calib/core/timing/logging_model.h>
#include <calib/core/timing/stamp_timing.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

// The timing diagnostics of raw streams in the calibrate JSON ("timing": {"streams": [...]}) and
// in the stdout summary.
namespace calib {

// One object per stream with every StreamTiming field under its own name (SI units: seconds).
nlohmann::json StreamTimingJson(const std::vector<StreamTiming>& streams);

// A few lines: one per stream (period, jitter, duplicates, gaps, verdict), then the notes of the
// streams whose stamps cannot be sample times or that show a free-running signature. Empty for
// no streams.
std::string StreamTimingSummary(const std::vector<StreamTiming>& streams);

// A simulated log's true timing for its truth file ("timing"): row, duplicate, skipped and held
// counts, and the true time of every written row's sample.
nlohmann::ordered_json LoggedTimingTruthJson(const LoggedTimingTruth& timing);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_STREAM_TIMING_REPORT_H_
