#ifndef CALIB_BENCHMARKS_BENCH_MICRO_H_
#define CALIB_BENCHMARKS_BENCH_MICRO_H_

#include <nlohmann/json.hpp>

// Google Benchmark micro-benchmarks: one LaserResidual evaluation with Jacobians, and
// CensiClosedForm on 1000 intervals. Prints Google Benchmark's console table; returns the runs.
namespace calib::bench {

nlohmann::json RunMicroBenchmarks();

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_MICRO_H_
