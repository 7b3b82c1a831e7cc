#ifndef CALIB_SOLVERS_BEARING_CALIBRATE_BEARING_INTERNAL_H_
#define CALIB_SOLVERS_BEARING_CALIBRATE_BEARING_INTERNAL_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/status.h>
#include <calib/solvers/bearing/bearing_bundle_adjustment.h>
#include <calib/solvers/bearing/calibrate_bearing.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

// The steps of CalibrateBearing shared by calibrate_bearing.cc (seed, noise, covariance) and
// calibrate_bearing_timing.cc (the timing model). Not part of the API.
namespace calib::bearing_calibration {

using Progress = std::function<void(const std::string&)>;
using BearingMask = std::vector<std::vector<bool>>;

// Noise levels by variance components, re-solving while they change; returns the final inlier
// flags. `summary` ends as that of the last solve.
StatusOr<BearingMask> EstimateNoise(const BearingCalibrationOptions& options,
                                    const Progress& progress, BearingProblem* problem,
                                    ceres::Solver::Summary* summary,
                                    BearingCalibrationResult* result);

// Tests τ, then the stamp jitter, on the fit in `*problem` (noise levels estimated); a part that
// is significant is modelled: `*problem` may be replaced by the fit with τ, and re-solved with the
// jitter's weights; `summary` and `inlier` follow. Fills result->timing.
Status ApplyTimingModel(const BearingLog& log, const BearingCalibrationOptions& options,
                        const Progress& progress, std::unique_ptr<BearingProblem>* problem,
                        ceres::Solver::Summary* summary, BearingMask* inlier,
                        BearingCalibrationResult* result);

// The free-running clock (bearing_clock.h) estimated on the fit in `problem` (the stamps' final
// fit, `inlier` its flags); when the log shows the clock and fixes its period, the calibration
// re-run on the clock's times (τ always modelled there) replaces `stamps` unless its bearing noise
// is significantly worse. Records the estimate and the re-fit in the result's timing either way.
StatusOr<BearingCalibrationResult> TrySensorClock(
    const BearingLog& log, const BearingCalibrationOptions& options, const Progress& progress,
    const BearingProblem& problem, const BearingMask& inlier, BearingCalibrationResult stamps);

// A warning for each stream whose stamp diagnostics (log.stream_timing, from the reader) show that
// its stamps cannot be the sample times.
void AddStreamTimingWarnings(const BearingLog& log, BearingCalibrationResult* result);

// After the covariance (result->covariance_scale set): σ of a modelled τ from the final fit.
Status FinishTiming(BearingProblem* problem, BearingCalibrationResult* result);

}  // namespace calib::bearing_calibration

#endif  // CALIB_SOLVERS_BEARING_CALIBRATE_BEARING_INTERNAL_H_
