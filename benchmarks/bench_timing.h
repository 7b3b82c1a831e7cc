#ifndef CALIB_BENCHMARKS_BENCH_TIMING_H_
#define CALIB_BENCHMARKS_BENCH_TIMING_H_

#include <nlohmann/json.hpp>

#include "benchmarks/bench_common.h"

namespace calib::bench {

// Section timing (issue 10, item 7): raw-stream logs from the laser simulator's logging model
// (core/timing/logging_model.h), calibrated with the stamps taken as sample times, against the
// jitter size and the logging pattern: per parameter the mean error in units of the reported σ
// (the bias) and the share of seeds within 2 σ (coverage, 95 % when the σ are right). Prints its
// table on stdout and returns every number as JSON. config.seeds logs per scenario; 0: 100 (10
// with config.quick).
nlohmann::ordered_json RunTimingBench(const BenchConfig& config);

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_TIMING_H_
