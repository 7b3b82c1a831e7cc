#ifndef CALIB_BENCHMARKS_BENCH_LASER_MONTE_CARLO_H_
#define CALIB_BENCHMARKS_BENCH_LASER_MONTE_CARLO_H_

#include <calib/core/laser/laser_params.h>

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "benchmarks/bench_common.h"

// Section laser_mc: Monte Carlo accuracy of the closed form, the trimmed closed form and the two
// Ceres refinements against the Cramér–Rao bound, over seeds, on simulated logs.
namespace calib::bench {

enum McMethod { kClosedForm = 0, kTrimmed, kRefineCauchy, kRefineNone, kNumMcMethods };
extern const char* const kMcMethodNames[kNumMcMethods];

struct McScenario {
  std::string kind;  // "gaussian", "anisotropic" or "wheel_noise".
  int intervals = 1000;
  Eigen::Vector3d scan_sigma = Eigen::Vector3d(0.001, 0.001, 0.002);
  double outlier_fraction = 0.0;
  double wheel_speed_noise = 0.0;
  int seeds = 100;  // Seeds 1 … seeds.
};

struct McMethodStats {
  int runs = 0;
  std::vector<int> failed_seeds;
  std::vector<std::string> failures;
  // Seeds whose error exceeds 5 √CRLB in some parameter: a wrong optimum, not noise.
  std::vector<int> gross_seeds;
  int warned = 0;  // Refinements: runs that came back with observability warnings.
  LaserParamVector bias = LaserParamVector::Zero();
  LaserParamVector rmse = LaserParamVector::Zero();
  LaserParamVector rmse_over_crlb = LaserParamVector::Zero();
  LaserParamVector mean_sigma = LaserParamVector::Zero();  // Refinements only.
  LaserParamVector coverage1 = LaserParamVector::Zero();   // Refinements only.
  LaserParamVector coverage2 = LaserParamVector::Zero();
  double median_seconds = 0.0;
};

// One seed of one scenario: every method's error (estimate − truth, θ wrapped) and, for the
// refinements, its reported sigma.
struct McSeedRun {
  bool ok[kNumMcMethods] = {};
  std::string message[kNumMcMethods];
  LaserParamVector error[kNumMcMethods];
  LaserParamVector sigma[kNumMcMethods];
  double seconds[kNumMcMethods] = {};
  bool warned[kNumMcMethods] = {};
  bool crlb_ok = false;
  LaserParamVector crlb_var = LaserParamVector::Zero();
  LaserParamVector diagonal_weighted_var = LaserParamVector::Zero();
};

struct McScenarioResult {
  McScenario scenario;
  LaserParamVector crlb_sd = LaserParamVector::Zero();  // √(mean over seeds of the bound).
  // √(mean) of the asymptotic variance with the residual's diagonal whitening (bench_crlb.h).
  LaserParamVector diagonal_weighted_sd = LaserParamVector::Zero();
  McMethodStats methods[kNumMcMethods];
  double seconds = 0.0;
  std::vector<McSeedRun> runs;  // Seeds 1 … S in order.
};

inline bool McHasSigma(int method) { return method == kRefineCauchy || method == kRefineNone; }

// Runs the grid (reduced in quick mode), prints the tables and returns the JSON; `results`
// receives the summaries for the plot.
nlohmann::json RunLaserMonteCarlo(const BenchConfig& config,
                                  std::vector<McScenarioResult>* results);

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_LASER_MONTE_CARLO_H_
