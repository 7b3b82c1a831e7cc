#ifndef CALIB_BENCHMARKS_BENCH_BEARING_H_
#define CALIB_BENCHMARKS_BENCH_BEARING_H_

#include <nlohmann/json.hpp>

#include "benchmarks/bench_common.h"

// The bearing-only calibration against Martinelli's simulations (INRIA RR-6796, §8.1, Table 4)
// and the Cramér–Rao bound. Prints its tables on stdout and returns every number as JSON:
//   1. Table 4: `seeds` simulated logs per σβ ∈ {1°, 3°, 5°} in the §8.1 setting (stated in the
//      output), Martinelli's closed form and the bundle adjustment side by side with √CRLB: mean
//      signed error, mean absolute error, the bound's mean absolute error √(2/π)·√CRLB, and for
//      the bundle adjustment the coverage of its reported sigmas and their ratio to the bound.
//   2. A non-circular trajectory (varying curvature), which the closed form cannot handle.
//   3. A scan of the geometry (start distance and direction of the landmark) for a setting in
//      which the bound would allow Table 4's errors.
namespace calib::bench {

// config.seeds logs per case; 0: 100 (10 with config.quick).
nlohmann::ordered_json RunBearingBench(const BenchConfig& config);

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_BEARING_H_
