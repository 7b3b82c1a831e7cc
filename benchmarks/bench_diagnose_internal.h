#ifndef CALIB_BENCHMARKS_BENCH_DIAGNOSE_INTERNAL_H_
#define CALIB_BENCHMARKS_BENCH_DIAGNOSE_INTERNAL_H_

#include <calib/core/laser/laser_simulator.h>
#include <calib/solvers/laser/laser_diagnosis.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "benchmarks/bench_common.h"

// The pieces of the diagnose section (bench_diagnose.cc: simulated logs and false alarms;
// bench_diagnose_power.cc: power, and the bearing problem's time offset).
namespace calib::bench::diagnose {

constexpr int kThreads = 2;
constexpr double kZ95 = 1.959963984540054;

// A simulated motion and noise regime (data/diagnose's recipes).
struct Regime {
  std::string name;
  std::string description;
  LaserSimOptions sim;
  bool forward_only = false;  // Simulate 2N intervals, drop backward ones, keep the first N.
};

Regime SmoothRegime(int intervals);
Regime PiecewiseRegime(int intervals);
Regime ForwardRegime(int intervals);
std::vector<LaserInterval> MakeLog(const Regime& regime, const LaserEffects& effects,
                                   double outliers, uint64_t seed, int intervals);
nlohmann::ordered_json SimJson(const Regime& regime, int intervals, double outliers);

// What one candidate's finding says on one log.
struct CandidateOutcome {
  bool present = false;
  bool testable = false;
  bool confounded = false;
  bool no_information = false;
  bool alone = false;  // p ≤ α: significant at the family level if it were tested alone.
  bool holm = false;   // Passed Holm's step-down (score test).
  bool adopted = false;
  int dof = 0;
  int step = 0;
  double statistic = 0.0;
  double p_value = 1.0;
  double one_step = 0.0;
  double one_step_stddev = 0.0;
  double value = 0.0;
  double stddev = 0.0;
};

struct LogOutcome {
  bool ok = false;
  std::string error;
  int intervals = 0;
  int testable = 0;  // Candidates neither confounded nor without information.
  std::vector<std::string> adopted;
  std::array<CandidateOutcome, kNumLaserEffects> candidates;
  double seconds = 0.0;
};

// DiagnoseLaser with default options on one log, and on n logs in parallel.
LogOutcome Diagnose(const std::vector<LaserInterval>& log);
std::vector<LogOutcome> RunLogs(int n, const std::function<std::vector<LaserInterval>(int)>& make);

// Wilson score interval of a binomial proportion.
struct Proportion {
  int k = 0, n = 0;
  double rate() const { return n > 0 ? static_cast<double>(k) / n : NAN; }
  double lower() const { return Bound(-1.0); }
  double upper() const { return Bound(1.0); }
  double Bound(double sign) const {
    if (n == 0) return NAN;
    const double p = rate(), z2 = kZ95 * kZ95;
    const double center = (p + z2 / (2.0 * n)) / (1.0 + z2 / n);
    const double half = kZ95 / (1.0 + z2 / n) * std::sqrt(p * (1.0 - p) / n + z2 / (4.0 * n * n));
    return std::clamp(center + sign * half, 0.0, 1.0);
  }
  nlohmann::ordered_json Json() const {
    return {{"count", k}, {"of", n}, {"rate", rate()}, {"ci95", {lower(), upper()}}};
  }
  std::string Text() const { return Format("%d/%d", k, n); }
  std::string Percent() const { return Format("%.1f%%", 100.0 * rate()); }
  std::string Interval() const {
    return Format("[%.1f, %.1f]%%", 100.0 * lower(), 100.0 * upper());
  }
};

double Mean(const std::vector<double>& v);
double StdDev(const std::vector<double>& v);

struct PowerScenario {
  LaserEffect effect;
  Regime regime;
  uint64_t seed_base;
  std::function<void(double, LaserEffects*)> set;
};

nlohmann::ordered_json RunPower(const PowerScenario& scenario, bool quick, int seeds,
                                int intervals);
nlohmann::ordered_json RunBearingTimeOffset(bool quick, int seeds);

}  // namespace calib::bench::diagnose

#endif  // CALIB_BENCHMARKS_BENCH_DIAGNOSE_INTERNAL_H_
