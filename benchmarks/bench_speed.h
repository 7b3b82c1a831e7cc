#ifndef CALIB_BENCHMARKS_BENCH_SPEED_H_
#define CALIB_BENCHMARKS_BENCH_SPEED_H_

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "benchmarks/bench_common.h"

// Section speed: wall time per stage and peak memory against N (each N in its own process, so
// the peak RSS is that N's), the log-log slope of the total, and Google Benchmark
// micro-benchmarks in the full mode.
namespace calib::bench {

nlohmann::json RunSpeed(const BenchConfig& config);

// The child side of RunSpeed: parses `path`, calibrates, prints one JSON line; returns the exit
// code.
int RunSpeedChild(const std::string& path, int64_t intervals);

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_SPEED_H_
