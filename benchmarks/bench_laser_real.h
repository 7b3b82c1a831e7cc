#ifndef CALIB_BENCHMARKS_BENCH_LASER_REAL_H_
#define CALIB_BENCHMARKS_BENCH_LASER_REAL_H_

#include <nlohmann/json.hpp>

#include "benchmarks/bench_common.h"

// Section laser_real: CalibrateLaser on the published Censi et al. recordings against the
// authors' results, the repeatability over the three disjoint subsets, and the wall time.
namespace calib::bench {

nlohmann::json RunLaserReal(const BenchConfig& config);

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_LASER_REAL_H_
