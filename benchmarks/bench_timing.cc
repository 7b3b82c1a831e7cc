#include "benchmarks/bench_timing.h"

#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/core/timing/logging_model.h>
#include <calib/solvers/laser/calibrate_laser.h>

#include <cmath>
#include <string>
#include <vector>

namespace calib::bench {
namespace {

struct TimingScenario {
  std::string pattern;    // What the logger does.
  double jitter_s = 0.0;  // The swept jitter (encoder stamp σ, or the pick-up σ).
  LoggingModel logging;
};

// The robot: a scanner free-running at 99.5 ms, encoders polled every 257 ms; the
// patterns add, one at a time and then together, what its logger did.
LoggingModel Base() {
  LoggingModel m;
  m.sensor_period_s = 0.0995;
  m.sensor_phase_s = 0.013;
  m.encoder_period_s = 0.257;
  return m;
}

std::vector<TimingScenario> Scenarios() {
  std::vector<TimingScenario> scenarios;
  scenarios.push_back({"clean timing", 0.0, Base()});
  for (const double sigma : {0.005, 0.010, 0.017}) {
    LoggingModel m = Base();
    m.encoder_stamp_jitter_s = sigma;
    scenarios.push_back({"encoder stamp jitter", sigma, m});
  }
  for (const double sigma : {0.0, 0.005, 0.010}) {
    LoggingModel m = Base();
    m.sensor_clock_drift = 2e-4;
    m.logger_period_s = 0.1;
    m.logger_jitter_s = sigma;
    scenarios.push_back({"logger pick-up (100 ms)", sigma, m});
  }
  LoggingModel robot = Base();
  robot.sensor_clock_drift = 2e-4;
  robot.logger_period_s = 0.1;
  robot.logger_jitter_s = 0.005;
  robot.encoder_poll_jitter_s = 0.003;
  robot.encoder_stamp_jitter_s = 0.017;
  robot.repeat_fraction = 0.01;
  scenarios.push_back({"robot-like (data/timing)", 0.017, robot});
  return scenarios;
}

// What the contract's stream reader does with exact duplicate rows: drops them.
LaserStreams DropRepeatedRows(const LaserStreams& streams) {
  LaserStreams kept;
  for (const EncoderSample& s : streams.odometry) {
    if (!kept.odometry.empty() && kept.odometry.back().t_s == s.t_s &&
        kept.odometry.back().left_rad == s.left_rad &&
        kept.odometry.back().right_rad == s.right_rad) {
      continue;
    }
    kept.odometry.push_back(s);
  }
  for (const StampedPose& p : streams.sensor_poses) {
    if (!kept.sensor_poses.empty() && kept.sensor_poses.back().t_s == p.t_s &&
        kept.sensor_poses.back().world_T_sensor == p.world_T_sensor) {
      continue;
    }
    kept.sensor_poses.push_back(p);
  }
  return kept;
}

// Per seed: (estimate − truth)/σ, NaN when the calibration failed.
struct SeedResult {
  LaserParamVector stamp_as_truth = LaserParamVector::Constant(NAN);
  // TIMING-AWARE: (estimate − truth)/σ of CalibrateLaserStreams
  // (<calib/solvers/timing/laser_timing_calibration.h>, branch wp-D) goes here.
  LaserParamVector timing_aware = LaserParamVector::Constant(NAN);
};

SeedResult RunSeed(const TimingScenario& scenario, int intervals, int seed) {
  LaserSimOptions sim;
  sim.num_intervals = intervals;
  sim.max_wheel_speed = 8.0;
  sim.scan_noise_sigma = Eigen::Vector3d(0.0005, 0.0005, 0.001);
  sim.seed = static_cast<uint64_t>(seed);
  LaserSimTruth truth;
  const LaserStreams streams =
      DropRepeatedRows(SimulateLoggedLaserStreams(sim, scenario.logging, &truth));
  SeedResult result;
  const LaserParamVector exact = LaserCalibration{truth.odometry, truth.base_T_sensor}.ToVector();
  const StatusOr<LaserLog> log =
      LaserLogFromStreams(streams.odometry, streams.sensor_poses, "simulation");
  if (!log.ok()) return result;
  const StatusOr<LaserCalibrationResult> fit = CalibrateLaser(log->intervals);
  if (fit.ok()) {
    result.stamp_as_truth = (fit->estimate.ToVector() - exact).cwiseQuotient(fit->stddev);
  }
  return result;
}

struct Summary {
  LaserParamVector bias = LaserParamVector::Zero();      // Mean of error/σ.
  LaserParamVector coverage = LaserParamVector::Zero();  // Share with |error| ≤ 2σ.
  int runs = 0;
};

Summary Summarize(const std::vector<LaserParamVector>& z) {
  Summary s;
  for (const LaserParamVector& v : z) {
    if (!v.allFinite()) continue;
    ++s.runs;
    s.bias += v;
    s.coverage += (v.cwiseAbs().array() <= 2.0).cast<double>().matrix();
  }
  if (s.runs > 0) {
    s.bias /= s.runs;
    s.coverage /= s.runs;
  }
  return s;
}

nlohmann::ordered_json SummaryJson(const Summary& s) {
  return {
      {"runs", s.runs}, {"bias_sigmas", ToJson(s.bias)}, {"coverage_2sigma", ToJson(s.coverage)}};
}

}  // namespace

nlohmann::ordered_json RunTimingBench(const BenchConfig& config) {
  const int seeds = config.seeds > 0 ? config.seeds : (config.quick ? 10 : 100);
  const int intervals = config.quick ? 1000 : 3000;
  std::printf(
      "\n== timing: stamps taken as sample times on logged raw streams (%d seeds x %d scans, "
      "rich motion up to 8 rad/s, scan noise 0.5 mm / 1 mrad) ==\n"
      "bias = mean (estimate - truth)/sigma; cover = share within 2 sigma (95 %% if right)\n",
      seeds, intervals);
  TextTable table({"logging pattern", "jitter ms", "bias r_l", "bias r_r", "bias b", "cover r_l",
                   "cover r_r", "cover b", "cover min", "timing-aware"});
  nlohmann::ordered_json json = nlohmann::ordered_json::array();
  for (const TimingScenario& scenario : Scenarios()) {
    std::vector<SeedResult> results(seeds);
    ParallelFor(seeds, config.threads,
                [&](int i) { results[i] = RunSeed(scenario, intervals, i + 1); });
    std::vector<LaserParamVector> stamp, aware;
    for (const SeedResult& r : results) {
      stamp.push_back(r.stamp_as_truth);
      aware.push_back(r.timing_aware);
    }
    const Summary s = Summarize(stamp);
    const Summary t = Summarize(aware);
    table.AddRow({scenario.pattern, Format("%.0f", scenario.jitter_s * 1e3),
                  Format("%+.2f", s.bias(0)), Format("%+.2f", s.bias(1)),
                  Format("%+.2f", s.bias(2)), Format("%.0f %%", 100 * s.coverage(0)),
                  Format("%.0f %%", 100 * s.coverage(1)), Format("%.0f %%", 100 * s.coverage(2)),
                  Format("%.0f %%", 100 * s.coverage.minCoeff()),
                  t.runs > 0 ? Format("cover min %.0f %%", 100 * t.coverage.minCoeff())
                             : std::string("(not yet)")});
    json.push_back({{"pattern", scenario.pattern},
                    {"jitter_s", scenario.jitter_s},
                    {"seeds", seeds},
                    {"intervals", intervals},
                    {"stamp_as_truth", SummaryJson(s)},
                    {"timing_aware", SummaryJson(t)}});
  }
  table.Print();
  return {{"scenarios", json}};
}

}  // namespace calib::bench
