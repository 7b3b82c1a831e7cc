#include <calib/core/laser/laser_log_io.h>
#include <calib/solvers/laser/calibrate_laser.h>

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

}  // namespace

nlohmann::ordered_json RunFalseAlarms(const std::vector<TimingSeedRun>& clean_runs) {
  std::printf(
      "\nFalse alarms on the %zu clean-timing logs of the table above (stamps = sample times):\n",
      clean_runs.size());
  Proportion any_adopted, timing_adopted, jitter_refit;
  std::map<std::string, int> adopted_names, clocks;
  int diagnose_failed = 0;
  for (const TimingSeedRun& run : clean_runs) {
    if (run.ok[kTimingAware]) ++clocks[run.sensor_clock];
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
  table.AddRow({"CalibrateLaser: boundary jitter significant (refit)", jitter_refit.Text(),
                jitter_refit.Percent(), jitter_refit.Interval()});
  table.AddRow({"diagnose adopts any effect", any_adopted.Text(), any_adopted.Percent(),
                any_adopted.Interval()});
  table.AddRow({"diagnose adopts a timing effect", timing_adopted.Text(), timing_adopted.Percent(),
                timing_adopted.Interval()});
  table.Print();
  std::string names;
  for (const auto& [name, count] : adopted_names) names += Format(" %s x%d", name.c_str(), count);
  std::printf("Adopted effects:%s; diagnose failed on %d logs.\n",
              names.empty() ? " none" : names.c_str(), diagnose_failed);
  nlohmann::ordered_json out = {{"logs", clean_runs.size()},
                                {"interval_jitter_refit", jitter_refit.Json()},
                                {"diagnose_any_adopted", any_adopted.Json()},
                                {"diagnose_timing_adopted", timing_adopted.Json()},
                                {"adopted_names", adopted_names},
                                {"diagnose_failed", diagnose_failed},
                                {"sensor_clock", clocks}};
  return out;
}

nlohmann::ordered_json RunTimingSpeed(const BenchConfig& config) {
  const std::vector<int> sizes =
      config.quick ? std::vector<int>{1000, 10000} : std::vector<int>{1000, 10000, 100000};
  std::printf(
      "\nSpeed: the clean pattern, seed 1, Ceres with %d threads; wall time of the "
      "calibration alone (simulation excluded):\n",
      config.threads);
  TextTable table({"intervals", "simulate s", "stamps_as_truth s", "timing_aware s"});
  nlohmann::ordered_json out;
  std::vector<double> ns, seconds;
  for (int n : sizes) {
    const Stopwatch sim_watch;
    LaserSimTruth truth;
    TimingPattern clean;
    const LaserStreams streams = SimulatePattern(clean, StudySimOptions(n, 1), &truth);
    const double sim_s = sim_watch.Seconds();
    const Stopwatch watch;
    const StatusOr<LaserLog> log =
        LaserLogFromStreams(streams.odometry, streams.sensor_poses, "simulated streams");
    LaserCalibrationOptions options;
    options.refinement.num_threads = config.threads;
    options.interval_jitter = false;
    const bool ok = log.ok() && CalibrateLaser(log->intervals, options).ok();
    const double stamps_s = watch.Seconds();
    table.AddRow(
        {std::to_string(n), Format("%.2f", sim_s), ok ? Format("%.3f", stamps_s) : "failed", "-"});
    out["runs"].push_back({{"intervals", n},
                           {"simulate_s", sim_s},
                           {"stamps_as_truth_s", stamps_s},
                           {"stamps_as_truth_ok", ok}});
    ns.push_back(n);
    seconds.push_back(stamps_s);
  }
  table.Print();
  if (ns.size() >= 2) out["log_log_slope_stamps_as_truth"] = LogLogSlope(ns, seconds);
  return out;
}

}  // namespace calib::bench::timing
