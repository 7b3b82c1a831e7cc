#ifndef CALIB_BENCHMARKS_BENCH_SECTIONS_H_
#define CALIB_BENCHMARKS_BENCH_SECTIONS_H_

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "benchmarks/bench_common.h"

// The sections of calib_bench that need no types of their own (laser_mc is in
// bench_laser_monte_carlo.h, diagnose in bench_diagnose.h). Each prints its tables on stdout
// and returns every number as JSON.
namespace calib::bench {

// Section laser_real: CalibrateLaser on the published Censi et al. recordings against the
// authors' results, the repeatability over the three disjoint subsets, and the wall time.
nlohmann::json RunLaserReal(const BenchConfig& config);

// Section bearing: the bearing-only calibration against Martinelli's simulations (INRIA RR-6796,
// §8.1, Table 4) and the Cramér–Rao bound. Prints its tables on stdout and returns every number as
// JSON:
//   1. Table 4: `seeds` simulated logs per σβ ∈ {1°, 3°, 5°} in the §8.1 setting (stated in the
//      output), Martinelli's closed form and the bundle adjustment side by side with √CRLB: mean
//      signed error, mean absolute error, the bound's mean absolute error √(2/π)·√CRLB, and for
//      the bundle adjustment the coverage of its reported sigmas and their ratio to the bound.
//   2. A non-circular trajectory (varying curvature), which the closed form cannot handle.
//   3. A scan of the geometry (start distance and direction of the landmark) for a setting in
//      which the bound would allow Table 4's errors.
//   4. The time of CalibrateBearing against the number of bearings (300 to 10 000; 3000 with
//      quick) on one weaving run, with its log-log slope.
// config.seeds logs per case; 0: 100 (10 with config.quick).
nlohmann::ordered_json RunBearingBench(const BenchConfig& config);

// Section speed: wall time per stage and peak memory against N (each N in its own process, so
// the peak RSS is that N's), the log-log slope of the total, and Google Benchmark
// micro-benchmarks in the full mode.
nlohmann::json RunSpeed(const BenchConfig& config);

// The child side of RunSpeed: parses `path`, calibrates, prints one JSON line; returns the exit
// code.
int RunSpeedChild(const std::string& path, int64_t intervals);

// Section scans: the scan matcher's speed and accuracy (360 and 1081 beams), the two-stage
// calibration's coverage over seeds, and a long recording (18 000 scans; 1200 with quick) end to
// end in process, with its errors in σ (where a matcher's bias shows first).
nlohmann::ordered_json RunScansBench(const BenchConfig& config);
// Part of it: the two-stage route against the refinement on the scan points.
nlohmann::ordered_json RunScanPointComparison(const BenchConfig& config);
// Part of it: a lidar's beam timing as drivers misstate it, trusted against checked.
nlohmann::ordered_json RunBeamTimingBench(const BenchConfig& config);

// Section robust_scale: the bias that slip outliers leave against the reported σ as N grows
// (10⁴, 10⁵, 10⁶ intervals; 5 % and 20 % slips), Cauchy alone against Cauchy then Tukey's biweight:
// mean z per parameter, 2σ coverage, d² against χ²₆.
nlohmann::ordered_json RunRobustScale(const BenchConfig& config);

// Google Benchmark micro-benchmarks: one LaserResidual evaluation with Jacobians, and
// CensiClosedForm on 1000 intervals. Prints Google Benchmark's console table; returns the runs.
nlohmann::json RunMicroBenchmarks();

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_SECTIONS_H_
