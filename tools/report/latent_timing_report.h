#ifndef CALIB_TOOLS_REPORT_LATENT_TIMING_REPORT_H_
#define CALIB_TOOLS_REPORT_LATENT_TIMING_REPORT_H_

#include <calib/solvers/timing/laser_timing_calibration.h>

#include <nlohmann/json.hpp>
#include <string>

// The timing-aware calibration of raw laser streams in the calibrate JSON
// ("timing": {"treatment": "latent_times", "latent_times": {...}}) and in the summary.
namespace calib {

// The clock model chosen, τ ± σ, the jitters, the period and drift of a free-running sensor, the
// models' scores, every sample's time ± σ (by its line in sensor_poses.csv), and the
// stamp-as-truth estimate for comparison. SI units.
nlohmann::ordered_json LatentTimingJson(const LaserTimingResult& result);

// The timing as a diagnose finding: effect "sample_times" (value: the mean offset of the
// estimated sample times from their stamps, s; "sensor_clock" stamps or free_running),
// significant when taking the stamps as sample times would move a parameter by more than 3 σ.
nlohmann::ordered_json LatentTimingFinding(const LaserTimingResult& result);
// A diagnosis JSON searched on the estimated sample times: the timing finding first (and adopted,
// as "sample_times", when significant) and the timing block.
void AddLatentTimingToDiagnosis(const LaserTimingResult& result, nlohmann::ordered_json* json);

// Two or three lines: the model, τ, the jitters or the clock, and how far the stamp-as-truth
// estimate was from this one.
std::string LatentTimingSummary(const LaserTimingResult& result);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_LATENT_TIMING_REPORT_H_
