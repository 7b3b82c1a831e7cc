#ifndef CALIB_CORE_LASER_WHEEL_READINGS_H_
#define CALIB_CORE_LASER_WHEEL_READINGS_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/status.h>

#include <cstddef>
#include <vector>

// Wheel readings in the form the calibration needs: cumulative angles in radians.
namespace calib {

// Cumulative wheel angles that a driver reported wrapped, into (−π, π] or [0, 2π): every value
// lies in one of those ranges and some step between consecutive samples exceeds π (half a turn
// between two encoder polls is no real motion). Adds the whole turns back in place and returns
// how many 2π jumps it removed (0: the angles were not wrapped and are unchanged). `values` is
// row-major with `stride` values per sample; `column` is the angle's.
int UnwrapWheelAngles(std::vector<double>* values, size_t stride, size_t column);

// Wheel readings in another unit (degrees, encoder counts) to radians: the interval speeds and
// steps and the raw encoder samples are multiplied by `radians_per_unit`. Fails unless it is
// positive and finite. The readers unwrap angles in radians only: a stream in another unit must
// hold cumulative readings.
Status ScaleWheelReadings(double radians_per_unit, LaserLog* log);

// Wheel readings in encoder ticks (N per wheel turn) to radians: ScaleWheelReadings by 2π/N.
// Fails unless N is positive and finite.
Status ConvertWheelTicks(double ticks_per_rev, LaserLog* log);

}  // namespace calib

#endif  // CALIB_CORE_LASER_WHEEL_READINGS_H_
