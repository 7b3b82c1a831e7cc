#ifndef CALIB_SOLVERS_BEARING_BEARING_INPUT_CHECKS_H_
#define CALIB_SOLVERS_BEARING_BEARING_INPUT_CHECKS_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/status.h>
#include <calib/solvers/bearing/calibrate_bearing.h>

// Input mistakes that the bearing calibration turns into a confident wrong number, read from its
// estimate against meta.json's nominal wheels (the bearing model fits a log with a wheel of the
// wrong sign as well as the right one: the error shows only in the parameters). With
// δ = δL/δR and ξ = δR/(B·δB):
// - δ < 0: one wheel's readings have the wrong sign (the left one where ξ > 0, else the right);
// - ξ < 0: the robot turns the other way than its wheels say (both wheels' signs, the columns
//   swapped, or the bearings' sign);
// - ξ·B = δR/δB outside [1/3, 3]: the wheel rotation is in another unit (degrees: π/180; ticks:
//   2π/N);
// - with an initial distance, a correction δR, δL or δB beyond [1/2, 2] (and 3σ from 1); without
//   one, radii that differ by more than 15 % (δ): the calibration is run again with the wheel
//   columns swapped, and when that reading is a robot (corrections within 20 % of 1, radii within
//   5 %, the bearings fitted as well) the columns are said to be swapped.
// None is corrected: the user fixes the file (Ok when the estimate is a robot).
namespace calib {

Status CheckBearingReadings(const BearingLog& log, const BearingCalibrationOptions& options,
                            const BearingCalibrationResult& result);

// `why` the log as given was refused (or Ok), unless its wheel columns exchanged give a robot
// fitted as well (its bearings' σβ within 10 % of `bearing_sigma_rad`): then the refusal that
// says so, with `as_given` (what the log as given showed).
Status SwappedOr(const BearingLog& log, const BearingCalibrationOptions& options,
                 const std::string& as_given, double bearing_sigma_rad, const Status& why);

// The log with each run's left and right wheel angles exchanged.
BearingLog WithWheelsSwapped(BearingLog log);

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_BEARING_INPUT_CHECKS_H_
