#include <calib/core/laser/laser_log_io.h>
#include <calib/solvers/laser/calibrate_laser.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "benchmarks/bench_diagnose_internal.h"
#include "benchmarks/bench_timing_study_internal.h"

namespace calib::bench::timing {
namespace {

using diagnose::Proportion;

// The candidates of the diagnosis that name timing (issue 10, item 4).
bool IsTimingEffect(const std::string& name) {
  return name == "stamp_jitter" || name == "sensor_clock";
}

std::string Seconds(double s) { return std::isfinite(s) ? Format("%.1f", s * 1e3) : "-"; }

}  // namespace

std::vector<std::string> TimingEstimatesHeader() {
  return {"pattern",
          "ok",
          "free_running",
          "tau ms (mean)",
          "tau true ms (mean)",
          "tau err ms (sd)",
          "|tau err|>2sd",
          "sigma_s ms",
          "sigma_e ms (med)",
          "sigma_e true"};
}

nlohmann::ordered_json AddTimingEstimates(const TimingPattern& pattern,
                                          const std::vector<TimingSeedRun>& runs,
                                          TextTable* table) {
  Proportion free_running, offset_significant;
  std::vector<double> offsets, true_offsets, errors, sensor_jitters, encoder_jitters;
  for (const TimingSeedRun& run : runs) {
    if (!run.ok[kTimingAware]) continue;
    ++free_running.n;
    ++offset_significant.n;
    free_running.k += run.sensor_clock == "free_running";
    const double error = run.time_offset_s - run.true_time_offset_s;
    offset_significant.k += std::abs(error) > 2.0 * run.time_offset_stddev_s;
    offsets.push_back(run.time_offset_s);
    true_offsets.push_back(run.true_time_offset_s);
    errors.push_back(error);
    sensor_jitters.push_back(run.sensor_jitter_s);
    encoder_jitters.push_back(run.encoder_jitter_s);
  }
  const double mean = diagnose::Mean(offsets), sd = diagnose::StdDev(errors);
  const double true_mean = diagnose::Mean(true_offsets);
  table->AddRow({pattern.name, std::to_string(free_running.n), free_running.Text(), Seconds(mean),
                 Seconds(true_mean), Seconds(sd), offset_significant.Text(),
                 Seconds(Median(sensor_jitters)), Seconds(Median(encoder_jitters)),
                 Seconds(pattern.logging.encoder_stamp_jitter_s)});
  return {{"runs", free_running.n},
          {"free_running_chosen", free_running.Json()},
          {"time_offset_mean_s", mean},
          {"true_time_offset_mean_s", true_mean},
          {"time_offset_error_sd_s", sd},
          {"time_offset_error_beyond_2sd", offset_significant.Json()},
          {"sensor_jitter_median_s", Median(sensor_jitters)},
          {"encoder_jitter_median_s", Median(encoder_jitters)},
          {"encoder_stamp_jitter_true_s", pattern.logging.encoder_stamp_jitter_s}};
}

nlohmann::ordered_json RunFalseAlarms(const std::vector<TimingSeedRun>& clean_runs) {
  std::printf(
      "\nFalse alarms on the %zu clean-timing logs of the table above (stamps = sample times):\n",
      clean_runs.size());
  Proportion any_adopted, timing_adopted, jitter_refit, free_running, offset;
  std::vector<double> sensor_jitters, encoder_jitters;
  std::map<std::string, int> adopted_names, clocks;
  int diagnose_failed = 0;
  for (const TimingSeedRun& run : clean_runs) {
    if (run.ok[kTimingAware]) {
      ++clocks[run.sensor_clock];
      ++free_running.n;
      ++offset.n;
      free_running.k += run.sensor_clock == "free_running";
      offset.k +=
          std::abs(run.time_offset_s - run.true_time_offset_s) > 2.0 * run.time_offset_stddev_s;
      sensor_jitters.push_back(run.sensor_jitter_s);
      encoder_jitters.push_back(run.encoder_jitter_s);
    }
    if (run.ok[kIntervalJitter]) {
      ++jitter_refit.n;
      jitter_refit.k += run.jitter_refit;
    }
    if (!run.diagnosed) {
      ++diagnose_failed;
      continue;
    }
    ++any_adopted.n;
    ++timing_adopted.n;
    bool timing = false;
    for (const std::string& name : run.adopted) {
      ++adopted_names[name];
      timing = timing || IsTimingEffect(name);
    }
    any_adopted.k += !run.adopted.empty();
    timing_adopted.k += timing;
  }
  TextTable table({"decision", "count", "rate", "95% CI"});
  table.AddRow({"timing_aware: chooses the free-running clock", free_running.Text(),
                free_running.Percent(), free_running.Interval()});
  table.AddRow({"timing_aware: |tau| > 2 sd (truth 0; ~5 % expected)", offset.Text(),
                offset.Percent(), offset.Interval()});
  table.AddRow({"CalibrateLaser: boundary jitter significant (refit)", jitter_refit.Text(),
                jitter_refit.Percent(), jitter_refit.Interval()});
  table.AddRow({"diagnose adopts any effect", any_adopted.Text(), any_adopted.Percent(),
                any_adopted.Interval()});
  table.AddRow({"diagnose adopts a timing effect", timing_adopted.Text(), timing_adopted.Percent(),
                timing_adopted.Interval()});
  table.Print();
  std::string names;
  for (const auto& [name, count] : adopted_names) names += Format(" %s x%d", name.c_str(), count);
  std::printf(
      "timing_aware jitter estimates (truth 0): sensor median %.2f ms, max %.2f ms; encoder "
      "median %.2f ms, max %.2f ms.\n",
      Median(sensor_jitters) * 1e3,
      sensor_jitters.empty()
          ? NAN
          : *std::max_element(sensor_jitters.begin(), sensor_jitters.end()) * 1e3,
      Median(encoder_jitters) * 1e3,
      encoder_jitters.empty()
          ? NAN
          : *std::max_element(encoder_jitters.begin(), encoder_jitters.end()) * 1e3);
  std::printf("Adopted effects:%s; diagnose failed on %d logs.\n",
              names.empty() ? " none" : names.c_str(), diagnose_failed);
  nlohmann::ordered_json out = {{"logs", clean_runs.size()},
                                {"timing_aware_free_running", free_running.Json()},
                                {"timing_aware_offset_beyond_2sd", offset.Json()},
                                {"timing_aware_sensor_jitter_s", sensor_jitters},
                                {"timing_aware_encoder_jitter_s", encoder_jitters},
                                {"interval_jitter_refit", jitter_refit.Json()},
                                {"diagnose_any_adopted", any_adopted.Json()},
                                {"diagnose_timing_adopted", timing_adopted.Json()},
                                {"adopted_names", adopted_names},
                                {"diagnose_failed", diagnose_failed},
                                {"sensor_clock", clocks}};
  return out;
}

nlohmann::ordered_json RunTimingSpeed(const BenchConfig& config, const TimingPattern& pattern) {
  // 10⁴ intervals take about 25 s with the first version of the timing-aware calibration.
  const std::vector<int> sizes =
      config.quick ? std::vector<int>{1000} : std::vector<int>{1000, 10000, 100000};
  std::printf(
      "\nSpeed: pattern %s, seed 1, Ceres with %d threads; wall time of each calibration "
      "alone (simulation excluded):\n",
      pattern.name.c_str(), config.threads);
  TextTable table({"intervals", "simulate s", "stamps_as_truth s", "timing_aware s", "rounds"});
  nlohmann::ordered_json out = {{"pattern", pattern.name}};
  std::vector<double> ns, seconds;
  for (int n : sizes) {
    const Stopwatch sim_watch;
    LaserSimTruth truth;
    const LaserStreams streams = SimulatePattern(pattern, StudySimOptions(n, 1), &truth);
    const double sim_s = sim_watch.Seconds();
    const Stopwatch watch;
    const StatusOr<LaserLog> log = StampsAsTruthLog(streams);
    LaserCalibrationOptions options;
    options.refinement.num_threads = config.threads;
    options.interval_jitter = false;
    const bool ok = log.ok() && CalibrateLaser(log->intervals, options).ok();
    const double stamps_s = watch.Seconds();
    LaserTimingOptions timing_options;
    timing_options.calibration.refinement.num_threads = config.threads;
    const Stopwatch timing_watch;
    const StatusOr<LaserTimingResult> timing = CalibrateLaserStreams(streams, timing_options);
    const double timing_s = timing_watch.Seconds();
    table.AddRow({std::to_string(n), Format("%.2f", sim_s),
                  ok ? Format("%.3f", stamps_s) : "failed",
                  timing.ok() ? Format("%.3f", timing_s) : "failed: " + timing.message(),
                  timing.ok() ? std::to_string(timing->rounds) : "-"});
    out["runs"].push_back({{"intervals", n},
                           {"simulate_s", sim_s},
                           {"stamps_as_truth_s", stamps_s},
                           {"stamps_as_truth_ok", ok},
                           {"timing_aware_s", timing_s},
                           {"timing_aware_ok", timing.ok()},
                           {"timing_aware_rounds", timing.ok() ? timing->rounds : 0}});
    if (timing.ok()) {
      ns.push_back(n);
      seconds.push_back(timing_s);
    }
  }
  table.Print();
  if (ns.size() >= 2) {
    const double slope = LogLogSlope(ns, seconds);
    std::printf("timing_aware: slope of log(time) against log(intervals) over %zu sizes: %.2f\n",
                ns.size(), slope);
    out["log_log_slope_timing_aware"] = slope;
  }
  return out;
}

}  // namespace calib::bench::timing
