#ifndef CALIB_BENCHMARKS_BENCH_TIMING_STUDY_INTERNAL_H_
#define CALIB_BENCHMARKS_BENCH_TIMING_STUDY_INTERNAL_H_

#include <calib/core/laser/laser_params.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/core/timing/logging_model.h>
#include <calib/solvers/timing/laser_timing_calibration.h>

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "benchmarks/bench_common.h"

// The pieces of the timing section (bench_timing_study.cc: patterns, seeds and the coverage
// tables; bench_timing_study_alarms.cc: false alarms and speed).
namespace calib::bench::timing {

// stamps_as_truth: the stream reader + CalibrateLaser without any timing model; interval_jitter:
// CalibrateLaser's weaker treatment for logs of intervals (boundary-stamp jitter propagated
// through the end speeds); timing_aware: the latent-time calibration of the raw streams.
enum TimingMethod { kStampsAsTruth = 0, kIntervalJitter, kTimingAware, kNumTimingMethods };
extern const char* const kTimingMethodNames[kNumTimingMethods];

struct TimingPattern {
  std::string name;
  std::string description;
  LoggingModel logging;
  // The scan matcher's errors: false, the simulator's (independent noise on each world pose, so
  // consecutive intervals' errors correlate by −½); true, chained matches (independent noise on
  // each interval between distinct samples, as an incremental ICP gives). Chained by default: with
  // the simulator's noise every method's σ is over-stated (the residuals' −½ correlation is not
  // modelled), and every coverage reads 100 %.
  bool chained_noise = true;
};

// One seed of one pattern.
struct TimingSeedRun {
  bool ok[kNumTimingMethods] = {};
  std::string message[kNumTimingMethods];
  LaserParamVector z[kNumTimingMethods];  // (estimate − truth)/reported σ, θ wrapped.
  double seconds[kNumTimingMethods] = {};
  int intervals = 0;
  // The timing-aware calibration's own timing estimates and decisions.
  double time_offset_s = 0.0;
  double time_offset_stddev_s = 0.0;
  double true_time_offset_s = 0.0;  // The simulated logger's mean lag (TrueTimeOffset).
  double sensor_jitter_s = 0.0;
  double encoder_jitter_s = 0.0;
  std::string sensor_clock;
  // CalibrateLaser's interval-jitter treatment: judged significant (and refitted), its σ_j.
  bool jitter_refit = false;
  double interval_jitter_s = 0.0;
  // `calib diagnose` on the stamp-as-truth intervals (clean pattern only).
  bool diagnosed = false;
  std::string diagnose_error;
  std::vector<std::string> adopted;
};

struct TimingMethodStats {
  int runs = 0;
  std::vector<std::string> failures;
  LaserParamVector mean_z = LaserParamVector::Zero();
  LaserParamVector rms_z = LaserParamVector::Zero();
  LaserParamVector coverage2 = LaserParamVector::Zero();
  double mean_seconds = 0.0;
};

// The base simulation of the study (motion, noise, truth) for `intervals` sensor intervals.
LaserSimOptions StudySimOptions(int intervals, uint64_t seed);

// Simulates one log of the pattern: the streams as logged, the truth, and τ's truth (the mean of
// true sample time − stamp over the distinct samples).
LaserStreams SimulatePattern(const TimingPattern& pattern, const LaserSimOptions& sim,
                             LaserSimTruth* truth, double* true_time_offset_s = nullptr);

// The stamp-as-truth log: exact repeated records dropped, then the stream reader.
StatusOr<LaserLog> StampsAsTruthLog(const LaserStreams& streams);

// Both calibrations on one log; `diagnose`: also DiagnoseLaser on the stamp-as-truth intervals.
TimingSeedRun RunSeed(const TimingPattern& pattern, int intervals, uint64_t seed, bool diagnose);

// The timing-aware calibration's own estimates on one pattern's logs: a row of `table` (header
// TimingEstimatesHeader()) and the JSON.
std::vector<std::string> TimingEstimatesHeader();
nlohmann::ordered_json AddTimingEstimates(const TimingPattern& pattern,
                                          const std::vector<TimingSeedRun>& runs, TextTable* table);

// Part 2 and part 3 of the section.
nlohmann::ordered_json RunFalseAlarms(const std::vector<TimingSeedRun>& clean_runs);
nlohmann::ordered_json RunTimingSpeed(const BenchConfig& config, const TimingPattern& pattern);

}  // namespace calib::bench::timing

#endif  // CALIB_BENCHMARKS_BENCH_TIMING_STUDY_INTERNAL_H_
