#ifndef CALIB_BENCHMARKS_BENCH_TIMING_STUDY_H_
#define CALIB_BENCHMARKS_BENCH_TIMING_STUDY_H_

#include <nlohmann/json.hpp>

#include "benchmarks/bench_common.h"

// Section timing: the laser–odometry calibration on raw streams whose stamps are what a logger
// wrote (issue 10). Prints its tables on stdout and returns every number as JSON:
//   1. Per logging pattern (clean stamps; encoder stamp scatter at a ~250 ms poll; a scanner
//      free-running at ~99.5 ms picked up by a ~100 ms logger; both with repeated records), over
//      seeds: per parameter the mean of z = (estimate − truth)/σ, its RMS and the 2σ coverage
//      P(|z| ≤ 2), for the stamp-as-truth calibration (stream reader + CalibrateLaser) and the
//      timing-aware one, and their run times.
//   2. False alarms on the clean-timing logs: the timing-aware calibration's own decisions and
//      `calib diagnose`'s adoption of any effect.
//   3. Speed of the timing-aware calibration on stream logs of 10³ … 10⁵ intervals.
// config.seeds logs per pattern; 0: 60 of 1000 intervals (8 of 500 with config.quick, which also
// leaves out the 5 and 10 ms encoder scatter and the 10⁴ and 10⁵ speed runs).
namespace calib::bench {

nlohmann::ordered_json RunTimingStudy(const BenchConfig& config);

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_TIMING_STUDY_H_
