#include <calib/core/laser/laser_simulator.h>
#include <calib/solvers/laser/calibrate_laser.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "benchmarks/bench_sections.h"

// Section robust_scale: whether gross slips bias the estimate by more than its σ as the log grows.
// Under Cauchy each slip keeps a pull of a²/‖r‖, a fixed bias, while σ shrinks as 1/√N; the
// redescending final passes (Tukey's biweight) give a slip no pull at all.
namespace calib::bench {
namespace {

// The 99 % point of χ²₆: d² = eᵀΣ⁻¹e beyond it in more than ~1 % of the logs is a bias.
constexpr double kChi2Six99 = 16.812;

struct ScaleCase {
  int intervals = 0;
  double slips = 0.0;
  int seeds = 0;
};

struct ScaleMethod {
  const char* name;
  double redescending_scale;
};
constexpr ScaleMethod kMethods[] = {{"cauchy", 0.0}, {"cauchy, then tukey (6)", 6.0}};
constexpr int kNumMethods = 2;

// What one method did over the seeds of one case.
struct ScaleStats {
  int runs = 0;
  int failed = 0;
  LaserParamVector mean_z = LaserParamVector::Zero();  // Mean of (estimate − truth)/σ.
  LaserParamVector worst_z = LaserParamVector::Zero();
  double coverage2 = 0.0;  // Share of |z| ≤ 2 over every parameter and seed.
  double mean_d2 = 0.0;
  double beyond_d2_99 = 0.0;  // Share of seeds with d² beyond χ²₆'s 99 % point.
  std::vector<double> seconds;
};

LaserSimOptions CaseSimulation(const ScaleCase& c, int seed) {
  LaserSimOptions sim;
  sim.num_intervals = c.intervals;
  sim.outlier_fraction = c.slips;
  sim.seed = static_cast<uint64_t>(seed);
  return sim;
}

void AddRun(const LaserCalibrationResult& result, const LaserCalibration& truth, double seconds,
            ScaleStats* stats) {
  const LaserParamVector error = LaserError(result.estimate, truth);
  const LaserParamVector z = error.cwiseQuotient(result.stddev);
  const double d2 = error.dot(result.covariance.ldlt().solve(error));
  ++stats->runs;
  stats->mean_z += z;
  stats->worst_z = stats->worst_z.cwiseMax(z.cwiseAbs());
  stats->coverage2 += (z.array().abs() <= 2.0).cast<double>().sum();
  stats->mean_d2 += d2;
  stats->beyond_d2_99 += d2 > kChi2Six99 ? 1.0 : 0.0;
  stats->seconds.push_back(seconds);
}

void Finish(ScaleStats* stats) {
  if (stats->runs == 0) return;
  stats->mean_z /= stats->runs;
  stats->coverage2 /= kNumLaserParams * stats->runs;
  stats->mean_d2 /= stats->runs;
  stats->beyond_d2_99 /= stats->runs;
}

// Every method on the same logs; logs of up to 10⁴ intervals run on the workers in parallel.
std::vector<ScaleStats> RunCase(const ScaleCase& c, int threads) {
  std::vector<std::vector<ScaleStats>> per_seed(c.seeds, std::vector<ScaleStats>(kNumMethods));
  const auto run_seed = [&](int s) {
    LaserSimTruth truth_sim;
    const LaserLog log = SimulateLaserLog(CaseSimulation(c, s + 1), &truth_sim);
    LaserCalibration truth;
    truth.odometry = truth_sim.odometry;
    truth.base_T_sensor = truth_sim.base_T_sensor;
    for (int m = 0; m < kNumMethods; ++m) {
      LaserCalibrationOptions options;
      options.refinement.redescending_scale = kMethods[m].redescending_scale;
      options.refinement.num_threads = c.intervals > 10000 ? threads : 1;
      const Stopwatch watch;
      const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log.intervals, options);
      if (!result.ok()) {
        ++per_seed[s][m].failed;
        continue;
      }
      AddRun(*result, truth, watch.Seconds(), &per_seed[s][m]);
    }
  };
  ParallelFor(c.seeds, c.intervals > 10000 ? 1 : threads, run_seed);
  std::vector<ScaleStats> stats(kNumMethods);
  for (int m = 0; m < kNumMethods; ++m) {
    for (int s = 0; s < c.seeds; ++s) {
      const ScaleStats& one = per_seed[s][m];
      stats[m].failed += one.failed;
      if (one.runs == 0) continue;
      ++stats[m].runs;
      stats[m].mean_z += one.mean_z;
      stats[m].worst_z = stats[m].worst_z.cwiseMax(one.worst_z);
      stats[m].coverage2 += one.coverage2;
      stats[m].mean_d2 += one.mean_d2;
      stats[m].beyond_d2_99 += one.beyond_d2_99;
      stats[m].seconds.push_back(one.seconds.front());
    }
    Finish(&stats[m]);
  }
  return stats;
}

std::vector<ScaleCase> Grid(const BenchConfig& config) {
  std::vector<ScaleCase> grid;
  for (double slips : {0.05, 0.2}) {
    if (config.quick) {
      grid.push_back({2000, slips, config.seeds > 0 ? config.seeds : 3});
      continue;
    }
    grid.push_back({10000, slips, config.seeds > 0 ? config.seeds : 100});
    grid.push_back({100000, slips, config.seeds > 0 ? std::min(config.seeds, 30) : 30});
    grid.push_back({1000000, slips, config.seeds > 0 ? std::min(config.seeds, 10) : 10});
  }
  return grid;
}

std::string Signed(double value) { return Format("%+.2f", value); }

}  // namespace

nlohmann::ordered_json RunRobustScale(const BenchConfig& config) {
  std::printf("\n=== Section robust_scale: bias under slips against N ===\n");
  std::printf(
      "Logs: SimulateLaserLog seeds 1..S (rich trajectory, default noise), a share of the "
      "intervals replaced by slip outliers (half wheel slips, half gross match errors of 20 σ). "
      "z = (estimate − truth)/σ per parameter; d² = eᵀΣ⁻¹e (χ²₆: mean 6, 99 %% point %.1f); "
      "2σ coverage over every parameter and seed.\n",
      kChi2Six99);
  TextTable table({"N", "slips", "method", "seeds", "mean z: r_l", "r_r", "b", "x", "y", "θ",
                   "max |z|", "2σ cov", "mean d²", "d²>99%", "s (median)"});
  nlohmann::ordered_json cases = nlohmann::ordered_json::array();
  for (const ScaleCase& c : Grid(config)) {
    const std::vector<ScaleStats> stats = RunCase(c, config.threads);
    for (int m = 0; m < kNumMethods; ++m) {
      const ScaleStats& s = stats[m];
      std::vector<std::string> row = {std::to_string(c.intervals), Format("%.0f %%", 100 * c.slips),
                                      kMethods[m].name, Format("%d (%d failed)", s.runs, s.failed)};
      for (int p = 0; p < kNumLaserParams; ++p) row.push_back(Signed(s.mean_z(p)));
      row.push_back(Format("%.1f", s.worst_z.maxCoeff()));
      row.push_back(Format("%.1f %%", 100 * s.coverage2));
      row.push_back(Format("%.1f", s.mean_d2));
      row.push_back(Format("%.0f %%", 100 * s.beyond_d2_99));
      row.push_back(Format("%.2f", Median(s.seconds)));
      table.AddRow(row);
      cases.push_back({{"intervals", c.intervals},
                       {"slips", c.slips},
                       {"method", kMethods[m].name},
                       {"runs", s.runs},
                       {"failed", s.failed},
                       {"mean_z", ToJson(s.mean_z)},
                       {"max_abs_z", ToJson(s.worst_z)},
                       {"coverage_2sigma", s.coverage2},
                       {"mean_d2", s.mean_d2},
                       {"share_d2_beyond_99", s.beyond_d2_99},
                       {"median_seconds", Median(s.seconds)}});
    }
    table.AddRule();
  }
  table.Print();
  return {{"cases", cases}};
}

}  // namespace calib::bench
