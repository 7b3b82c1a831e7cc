#ifndef CALIB_CORE_LASER_LASER_PLAUSIBILITY_H_
#define CALIB_CORE_LASER_LASER_PLAUSIBILITY_H_

#include <calib/core/laser/laser_log.h>

// Physical bounds on a log's intervals, applied by every laser reader before anything reaches a
// solver. An interval is implausible when
//   - any value is beyond 1e9 (no unit explains it: a glitch such as 5e307), or
//   - it turns by more than a full turn (|sm_θ| > 2π), or
//   - its T, a wheel's rotation |φ·T| or its displacement |sm_xy| is more than 1000 times the
//     log's own scale for that quantity (the (m+1)-th largest value, m = max(2, n/50), so that a
//     few glitches cannot raise the scale they are judged by).
// A handful of implausible intervals are glitches: dropped (the next kept one marked as after a
// gap) and counted in one warning naming the first. Many of one kind are the log's unit, not a
// glitch (θ in degrees turns by more than 2π often): kept, for the input checks to name.
namespace calib {

void DropImplausibleIntervals(LaserLog* log);

}  // namespace calib

#endif  // CALIB_CORE_LASER_LASER_PLAUSIBILITY_H_
