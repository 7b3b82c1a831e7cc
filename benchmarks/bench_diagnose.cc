#include "benchmarks/bench_diagnose.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "benchmarks/bench_common.h"
#include <calib/core/bearing/bearing_simulator.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/solvers/bearing/bearing_diagnosis.h>
#include <calib/solvers/laser/laser_diagnosis.h>
#include <calib/solvers/stats/score_test.h>

namespace calib::bench {
namespace {

constexpr int kThreads = 2;
constexpr double kZ95 = 1.959963984540054;

// A simulated motion and noise regime (data/diagnose's recipes).
struct Regime {
  std::string name;
  std::string description;
  LaserSimOptions sim;
  bool forward_only = false;  // Simulate 2N intervals, drop backward ones, keep the first N.
};

// `calib simulate`'s defaults: smooth speeds of both signs through a 0.5 s lag.
Regime SmoothRegime(int intervals) {
  Regime r;
  r.name = "smooth";
  r.description =
      "calib simulate defaults (smooth speeds, tau 0.5 s, segments 6 s, sigma_th 2 mrad)";
  r.sim.num_intervals = intervals;
  return r;
}

// Speeds constant within intervals, commanded anew at (almost) every scan (data/diagnose's
// time_offset and clean_piecewise_outliers).
Regime PiecewiseRegime(int intervals) {
  Regime r;
  r.name = "piecewise";
  r.description = "speeds constant within intervals (tau 0, segments 0.8 s), sigma_th 10 mrad";
  r.sim.num_intervals = intervals;
  r.sim.speed_time_constant_s = 0.0;
  r.sim.segment_mean_s = 0.8;
  r.sim.scan_noise_sigma = Eigen::Vector3d(0.001, 0.001, 0.01);
  return r;
}

// A faster robot that drives forward only (data/diagnose's lateral_slip).
Regime ForwardRegime(int intervals) {
  Regime r;
  r.name = "forward_only";
  r.description =
      "forward-only (backward intervals dropped, gaps kept), max wheel speed 4 rad/s, 2N "
      "simulated -> first N kept";
  r.sim.num_intervals = 2 * intervals;
  r.sim.max_wheel_speed = 4.0;
  r.forward_only = true;
  return r;
}

std::vector<LaserInterval> MakeLog(const Regime& regime, const LaserEffects& effects,
                                   double outliers, uint64_t seed, int intervals) {
  LaserSimOptions sim = regime.sim;
  sim.effects = effects;
  sim.outlier_fraction = outliers;
  sim.seed = seed;
  std::vector<LaserInterval> log = SimulateLaserLog(sim).intervals;
  if (regime.forward_only) {
    log = DropBackwardIntervals(log, sim.odometry);
    if (log.size() > static_cast<size_t>(intervals)) log.resize(intervals);
  }
  for (size_t k = 0; k < log.size(); ++k) log[k].record = static_cast<int>(k + 1);
  return log;
}

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

LogOutcome Diagnose(const std::vector<LaserInterval>& log) {
  LogOutcome out;
  out.intervals = static_cast<int>(log.size());
  const LaserDiagnosisOptions options;
  const Stopwatch watch;
  const StatusOr<LaserDiagnosis> d = DiagnoseLaser(log, options);
  out.seconds = watch.Seconds();
  if (!d.ok()) {
    out.error = d.message();
    return out;
  }
  out.ok = true;
  for (LaserEffect e : d->adopted) out.adopted.push_back(LaserEffectName(e));
  for (const LaserFinding& f : d->findings) {
    CandidateOutcome& c = out.candidates[static_cast<int>(f.effect)];
    c.present = true;
    c.confounded = f.confounded;
    c.no_information = f.no_information;
    c.testable = !f.confounded && !f.no_information;
    if (c.testable) ++out.testable;
    c.alone = c.testable && f.p_value <= options.alpha;
    c.holm = f.score_significant;
    c.adopted = f.significant;
    c.dof = f.dof;
    c.step = f.step;
    c.statistic = f.statistic;
    c.p_value = f.p_value;
    if (f.one_step.size() > 0) c.one_step = f.one_step(0);
    if (f.one_step_stddev.size() > 0) c.one_step_stddev = f.one_step_stddev(0);
    c.value = f.value;
    c.stddev = f.stddev;
  }
  return out;
}

std::vector<LogOutcome> RunLogs(int n, const std::function<std::vector<LaserInterval>(int)>& make) {
  std::vector<LogOutcome> outcomes(n);
  ParallelFor(n, kThreads, [&](int i) { outcomes[i] = Diagnose(make(i)); });
  return outcomes;
}

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

double NormalCdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

// The χ²₁ critical value at level p: ChiSquareSurvival(c, 1) = p (bisection).
double ChiSquare1Critical(double p) {
  double lo = 0.0, hi = 400.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (ChiSquareSurvival(mid, 1) > p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// P(χ²₁(λ) > c) = P(|Z + √λ| > √c).
double NoncentralChiSquare1Tail(double c, double lambda) {
  const double a = std::sqrt(c), m = std::sqrt(lambda);
  return NormalCdf(-a - m) + NormalCdf(m - a);
}

double Mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return v.empty() ? NAN : s / v.size();
}
double StdDev(const std::vector<double>& v) {
  if (v.size() < 2) return NAN;
  const double m = Mean(v);
  double s = 0.0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / (v.size() - 1));
}

// Two significant digits.
double Round2(double x) {
  if (x == 0.0) return 0.0;
  const double scale = std::pow(10.0, std::floor(std::log10(std::abs(x))) - 1.0);
  return std::round(x / scale) * scale;
}

nlohmann::ordered_json SimJson(const Regime& regime, int intervals, double outliers) {
  const LaserSimOptions& s = regime.sim;
  return {{"regime", regime.name},
          {"description", regime.description},
          {"intervals", intervals},
          {"simulated_intervals", s.num_intervals},
          {"forward_only", regime.forward_only},
          {"speed_time_constant_s", s.speed_time_constant_s},
          {"segment_mean_s", s.segment_mean_s},
          {"max_wheel_speed", s.max_wheel_speed},
          {"scan_noise_sigma", ToJson(s.scan_noise_sigma)},
          {"outlier_fraction", outliers},
          {"mean_interval_s", s.mean_interval_s}};
}

// --- 1. False alarms on clean logs ---------------------------------------------------------

struct CleanGroup {
  std::string name;
  Regime regime;
  double outliers = 0.0;
  uint64_t seed_base = 0;
  std::vector<LogOutcome> logs;
};

nlohmann::ordered_json RunFalseAlarms(bool quick, int seeds, int intervals) {
  const int per_half = seeds > 0 ? seeds : (quick ? 10 : 100);
  const int smooth_n = (per_half + 1) / 2, piecewise_n = per_half / 2;
  // Seeds: 1000·(group + 1) + i, i = 0 … count − 1.
  std::vector<CleanGroup> groups = {
      {"smooth", SmoothRegime(intervals), 0.0, 1000, {}},
      {"piecewise", PiecewiseRegime(intervals), 0.0, 2000, {}},
      {"smooth + 5% outliers", SmoothRegime(intervals), 0.05, 3000, {}},
      {"piecewise + 5% outliers", PiecewiseRegime(intervals), 0.05, 4000, {}},
  };
  const LaserDiagnosisOptions defaults;
  std::printf(
      "\n== diagnose 1: false alarms on clean logs (DiagnoseLaser defaults: alpha %.3g per step, "
      "max %d effects, %d CV blocks) ==\n",
      defaults.alpha, defaults.max_effects, defaults.cv_blocks);
  std::printf("%d logs without and %d with 5%% slip outliers (x20 sigma), %d intervals each:\n",
              per_half, per_half, intervals);
  const Stopwatch watch;
  for (size_t g = 0; g < groups.size(); ++g) {
    CleanGroup& group = groups[g];
    const int n = g % 2 == 0 ? smooth_n : piecewise_n;
    std::printf("  %-24s %3d logs, seeds %llu..%llu: %s\n", group.name.c_str(), n,
                static_cast<unsigned long long>(group.seed_base),
                static_cast<unsigned long long>(group.seed_base + n - 1),
                group.regime.description.c_str());
    group.logs = RunLogs(n, [&](int i) {
      return MakeLog(group.regime, LaserEffects(), group.outliers, group.seed_base + i, intervals);
    });
  }
  const double seconds = watch.Seconds();

  // Any adoption, per group and pooled.
  TextTable table(
      {"logs", "n", "adopted any", "rate", "95% CI", "nothing adopted", "failed", "median s/log"});
  nlohmann::ordered_json groups_json = nlohmann::ordered_json::array();
  Proportion all, without, with;
  std::vector<double> all_seconds;
  std::map<std::string, int> adopted_names;
  nlohmann::ordered_json alarms = nlohmann::ordered_json::array();
  int failed_total = 0;
  for (size_t g = 0; g < groups.size(); ++g) {
    const CleanGroup& group = groups[g];
    Proportion p;
    int failed = 0;
    std::vector<double> secs;
    for (size_t i = 0; i < group.logs.size(); ++i) {
      const LogOutcome& log = group.logs[i];
      secs.push_back(log.seconds);
      all_seconds.push_back(log.seconds);
      if (!log.ok) {
        ++failed;
        continue;
      }
      ++p.n;
      if (!log.adopted.empty()) {
        ++p.k;
        for (const std::string& name : log.adopted) ++adopted_names[name];
        alarms.push_back(
            {{"group", group.name}, {"seed", group.seed_base + i}, {"adopted", log.adopted}});
      }
    }
    failed_total += failed;
    all.k += p.k;
    all.n += p.n;
    Proportion& half = group.outliers > 0 ? with : without;
    half.k += p.k;
    half.n += p.n;
    table.AddRow({group.name, std::to_string(p.n), std::to_string(p.k), p.Percent(), p.Interval(),
                  Format("%.1f%%", 100.0 * (1.0 - p.rate())), std::to_string(failed),
                  Format("%.2f", Median(secs))});
    groups_json.push_back({{"name", group.name},
                           {"simulation", SimJson(group.regime, intervals, group.outliers)},
                           {"seeds", {group.seed_base, group.seed_base + group.logs.size() - 1}},
                           {"false_alarm", p.Json()},
                           {"failed", failed},
                           {"median_seconds", Median(secs)}});
  }
  table.AddRule();
  const auto pooled_row = [&](const std::string& name, const Proportion& p) {
    table.AddRow({name, std::to_string(p.n), std::to_string(p.k), p.Percent(), p.Interval(),
                  Format("%.1f%%", 100.0 * (1.0 - p.rate())), "", ""});
  };
  pooled_row("without outliers", without);
  pooled_row("with 5% outliers", with);
  pooled_row("all clean logs", all);
  table.Print();
  const bool target_met = 1.0 - all.rate() >= 0.95;
  const bool target_significant = all.upper() < 0.05;
  std::printf(
      "Target (nothing adopted on >= 95%% of clean logs): %s (%.1f%% clean; the false-alarm "
      "rate's 95%% upper bound %.1f%% %s 5%%). %d failed runs. %.1f s wall.\n",
      target_met ? "MET" : "NOT MET", 100.0 * (1.0 - all.rate()), 100.0 * all.upper(),
      target_significant ? "<" : ">=", failed_total, seconds);
  if (!adopted_names.empty()) {
    std::printf("Adopted on clean logs:");
    for (const auto& [name, count] : adopted_names) std::printf(" %s x%d", name.c_str(), count);
    std::printf("\n");
  }

  // Per candidate, pooled over the groups.
  std::printf(
      "\nPer candidate over all %d clean logs (the finding's last score test; 'alone': p <= "
      "alpha = %.3g, i.e. significant at the family level without the multiplicity correction; "
      "'Holm': passed the step-down; per group S, P, S+o, P+o):\n",
      all.n, defaults.alpha);
  TextTable candidates({"candidate", "testable", "confounded", "no info", "dof", "mean stat",
                        "alone", "alone 95% CI", "alone S/P/So/Po", "Holm", "adopted"});
  nlohmann::ordered_json candidates_json = nlohmann::ordered_json::array();
  for (LaserEffect effect : AllLaserEffects()) {
    const int e = static_cast<int>(effect);
    Proportion testable, confounded, no_info, alone, holm, adopted;
    std::vector<double> stats;
    std::string per_group;
    int dof = 0;
    for (size_t g = 0; g < groups.size(); ++g) {
      int group_alone = 0;
      for (const LogOutcome& log : groups[g].logs) {
        if (!log.ok) continue;
        const CandidateOutcome& c = log.candidates[e];
        ++testable.n;
        ++confounded.n;
        ++no_info.n;
        ++adopted.n;
        testable.k += c.testable;
        confounded.k += c.confounded;
        no_info.k += c.no_information;
        adopted.k += c.adopted;
        if (!c.testable) continue;
        dof = std::max(dof, c.dof);
        stats.push_back(c.statistic);
        ++alone.n;
        ++holm.n;
        alone.k += c.alone;
        holm.k += c.holm;
        group_alone += c.alone;
      }
      per_group += (g > 0 ? "/" : "") + std::to_string(group_alone);
    }
    const std::string name = LaserEffectName(effect);
    const bool tested = alone.n > 0;
    candidates.AddRow({name, testable.Percent(), confounded.Percent(), no_info.Percent(),
                       tested ? std::to_string(dof) : "-",
                       tested ? Format("%.2f", Mean(stats)) : "-", tested ? alone.Text() : "-",
                       tested ? alone.Interval() : "-", tested ? per_group : "-",
                       tested ? holm.Text() : "-", adopted.Text()});
    candidates_json.push_back({{"candidate", name},
                               {"testable", testable.Json()},
                               {"confounded", confounded.Json()},
                               {"no_information", no_info.Json()},
                               {"dof", dof},
                               {"mean_statistic", tested ? Mean(stats) : NAN},
                               {"alone_significant", alone.Json()},
                               {"alone_significant_per_group", per_group},
                               {"holm_significant", holm.Json()},
                               {"adopted", adopted.Json()}});
  }
  candidates.Print();
  std::printf(
      "(mean stat: the score statistic's mean over the logs where it is testable; chi2_dof "
      "has mean dof, wheel_radius_change is a sup over change times.)\n");

  nlohmann::ordered_json j;
  j["intervals"] = intervals;
  j["logs_without_outliers"] = per_half;
  j["logs_with_outliers"] = per_half;
  j["alpha"] = defaults.alpha;
  j["groups"] = groups_json;
  j["false_alarm_without_outliers"] = without.Json();
  j["false_alarm_with_outliers"] = with.Json();
  j["false_alarm"] = all.Json();
  j["nothing_adopted_rate"] = 1.0 - all.rate();
  j["target_nothing_adopted"] = 0.95;
  j["target_met"] = target_met;
  j["target_met_at_95_confidence"] = target_significant;
  j["alarms"] = alarms;
  j["failed"] = failed_total;
  j["candidates"] = candidates_json;
  j["median_seconds_per_log"] = Median(all_seconds);
  j["wall_seconds"] = seconds;
  return j;
}

// --- 2. Power against effect size ----------------------------------------------------------

struct PowerScenario {
  LaserEffect effect;
  Regime regime;
  uint64_t seed_base;
  std::function<void(double, LaserEffects*)> set;
};

nlohmann::ordered_json RunPower(const PowerScenario& scenario, bool quick, int seeds,
                                int intervals) {
  const int e = static_cast<int>(scenario.effect);
  const std::string name = LaserEffectName(scenario.effect);
  const int per_size = seeds > 0 ? seeds : (quick ? 8 : 40);
  const int pilots = quick ? 2 : 4;
  const std::vector<double> multiples = {1.0, 2.0, 3.0, 4.0, 6.0};
  const LaserDiagnosisOptions defaults;
  const Stopwatch watch;

  // Pilot: σ_γ of the one-step estimate on logs without the effect.
  const uint64_t pilot_base = scenario.seed_base + 900;
  const std::vector<LogOutcome> pilot = RunLogs(pilots, [&](int i) {
    return MakeLog(scenario.regime, LaserEffects(), 0.0, pilot_base + i, intervals);
  });
  std::vector<double> pilot_sd;
  for (const LogOutcome& log : pilot) {
    if (log.ok && log.candidates[e].testable) pilot_sd.push_back(log.candidates[e].one_step_stddev);
  }
  const double sigma_pilot = Mean(pilot_sd);
  std::printf("\n== diagnose 2: power for %s (%s) ==\n", name.c_str(),
              scenario.regime.name.c_str());
  std::printf("Simulation: %s; %d intervals; no outliers.\n", scenario.regime.description.c_str(),
              intervals);
  std::printf(
      "Pilot: %d logs without the effect (seeds %llu..%llu): one-step sigma_gamma = %.3g ms.\n",
      pilots, static_cast<unsigned long long>(pilot_base),
      static_cast<unsigned long long>(pilot_base + pilots - 1), sigma_pilot * 1e3);
  if (!(sigma_pilot > 0.0)) {
    std::printf("The pilot found no testable %s; skipped.\n", name.c_str());
    return {{"effect", name}, {"skipped", "not testable in the pilot"}};
  }

  TextTable table({"gamma ms", "gamma/sd", "sd ms", "lambda", "m", "theory", "score rej", "95% CI",
                   "Holm", "adopted", "95% CI", "others", "one-step ms", "estimate ms", "seeds"});
  nlohmann::ordered_json sizes = nlohmann::ordered_json::array();
  std::vector<int> all_m;
  for (size_t s = 0; s < multiples.size(); ++s) {
    const double gamma = Round2(multiples[s] * sigma_pilot);
    const uint64_t base = scenario.seed_base + 100 * s;
    LaserEffects effects;
    scenario.set(gamma, &effects);
    const std::vector<LogOutcome> logs = RunLogs(per_size, [&](int i) {
      return MakeLog(scenario.regime, effects, 0.0, base + i, intervals);
    });
    std::vector<double> sds, estimates, one_steps;
    std::map<int, int> m_count;
    int failed = 0;
    for (const LogOutcome& log : logs) {
      if (!log.ok) {
        ++failed;
        continue;
      }
      ++m_count[log.testable];
      all_m.push_back(log.testable);
      const CandidateOutcome& c = log.candidates[e];
      if (c.testable) {
        sds.push_back(c.one_step_stddev);
        one_steps.push_back(c.one_step);
      }
      if (c.adopted) estimates.push_back(c.value);
    }
    // The number of testable candidates most logs have.
    int m = 0, m_logs = -1;
    for (const auto& [count, k] : m_count) {
      if (k > m_logs) m = count, m_logs = k;
    }
    const double level = defaults.alpha / std::max(m, 1);
    const double c = ChiSquare1Critical(level);
    const double sd = Mean(sds);
    const double lambda = std::pow(gamma / sd, 2);
    const double theory = NoncentralChiSquare1Tail(c, lambda);
    Proportion reject, holm, adopted, others;
    for (const LogOutcome& log : logs) {
      if (!log.ok) continue;
      const CandidateOutcome& cand = log.candidates[e];
      ++reject.n;
      ++holm.n;
      ++adopted.n;
      ++others.n;
      reject.k += cand.testable && cand.statistic > c;
      holm.k += cand.holm;
      adopted.k += cand.adopted;
      others.k += static_cast<int>(log.adopted.size()) > (cand.adopted ? 1 : 0);
    }
    std::string estimate = "-";
    if (estimates.size() == 1) estimate = Format("%.2f", estimates[0] * 1e3);
    if (estimates.size() > 1) {
      estimate = Format("%.2f +- %.2f", Mean(estimates) * 1e3, StdDev(estimates) * 1e3);
    }
    const std::string one_step =
        Format("%.2f +- %.2f", Mean(one_steps) * 1e3, StdDev(one_steps) * 1e3);
    table.AddRow({Format("%.3g", gamma * 1e3), Format("%.2f", gamma / sd), Format("%.2f", sd * 1e3),
                  Format("%.2f", lambda), std::to_string(m), Format("%.1f%%", 100.0 * theory),
                  reject.Percent(), reject.Interval(), holm.Percent(), adopted.Percent(),
                  adopted.Interval(), others.Text(), one_step, estimate,
                  Format("%llu..%llu", static_cast<unsigned long long>(base),
                         static_cast<unsigned long long>(base + per_size - 1))});
    sizes.push_back({{"gamma", gamma},
                     {"multiple_of_pilot_sigma", multiples[s]},
                     {"seeds", {base, base + per_size - 1}},
                     {"logs", per_size},
                     {"failed", failed},
                     {"sigma_gamma_mean", sd},
                     {"gamma_over_sigma", gamma / sd},
                     {"lambda", lambda},
                     {"testable_candidates", m},
                     {"holm_first_level", level},
                     {"critical_value", c},
                     {"theoretical_power", theory},
                     {"score_rejection", reject.Json()},
                     {"holm_significant", holm.Json()},
                     {"detection", adopted.Json()},
                     {"other_effect_adopted", others.Json()},
                     {"one_step_mean", Mean(one_steps)},
                     {"one_step_stddev_empirical", StdDev(one_steps)},
                     {"adopted_value_mean", estimates.empty() ? NAN : Mean(estimates)},
                     {"adopted_value_stddev", StdDev(estimates)}});
  }
  table.Print();
  std::printf(
      "(theory: P(chi2_1(lambda) > c), lambda = (gamma/sd)^2, sd the mean reported one-step "
      "sigma_gamma, c the chi2_1 critical value at the first Holm level alpha/m = %.3g/m, m the "
      "testable candidates; score rej: statistic > c; Holm: passed the step-down; adopted: "
      "the detection; others: logs adopting another effect; one-step: the one-step estimates, mean "
      "+- sd; estimate: adopted values, mean +- "
      "sd. %.1f s wall.)\n",
      defaults.alpha, watch.Seconds());
  return {{"effect", name},
          {"unit", "s"},
          {"simulation", SimJson(scenario.regime, intervals, 0.0)},
          {"pilot",
           {{"logs", pilots},
            {"seeds", {pilot_base, pilot_base + pilots - 1}},
            {"sigma_gamma", sigma_pilot}}},
          {"alpha", defaults.alpha},
          {"sizes", sizes},
          {"wall_seconds", watch.Seconds()}};
}

// The bearing problem's one candidate, time_offset, on the weaving run of data/diagnose
// (WeavingRun: 300 s, 2 Hz bearings, σβ = 1°, K = 1e-3): false alarms on null logs, and the
// detection rate against τ next to the score test's power χ²₁(λ = τ²/σ_τ²) at the level, σ_τ the
// mean one-step standard deviation of the null logs.
nlohmann::ordered_json RunBearingTimeOffset(bool quick, int seeds) {
  const int nulls = seeds > 0 ? seeds : (quick ? 4 : 100);
  const int per_size = seeds > 0 ? seeds : (quick ? 2 : 30);
  const std::vector<double> taus = {0.05, 0.1, 0.15};
  struct Outcome {
    bool ok = false;
    bool adopted = false;
    double value = 0.0, stddev = 0.0, one_step_stddev = 0.0;
  };
  const auto run = [](double tau, uint64_t seed) {
    BearingSimOptions o;
    o.seed = seed;
    o.encoder_rate_hz = 5.0;
    o.bearing_rate_hz = 2.0;
    o.bearing_noise_rad = M_PI / 180.0;
    o.initial_distance_run = 1;
    o.time_offset_s = tau;
    o.runs = {WeavingRun()};
    Outcome out;
    const StatusOr<BearingDiagnosis> d = DiagnoseBearing(SimulateBearingLog(o));
    if (!d.ok()) return out;
    out.ok = true;
    const BearingFinding& f = d->findings[0];
    out.adopted = f.significant;
    out.value = f.value;
    out.stddev = f.stddev;
    out.one_step_stddev = f.one_step_stddev(0);
    return out;
  };
  const BearingDiagnosisOptions defaults;
  std::printf(
      "\n== diagnose 3: bearing time_offset (weaving run, 300 s, 2 Hz bearings, σβ 1°; "
      "alpha %.3g) ==\n",
      defaults.alpha);
  const Stopwatch watch;
  std::vector<Outcome> null(nulls);
  ParallelFor(nulls, kThreads, [&](int i) { null[i] = run(0.0, 50000 + i); });
  Proportion alarms;
  std::vector<double> sigmas;
  int failed = 0;
  for (const Outcome& o : null) {
    if (!o.ok) {
      ++failed;
      continue;
    }
    ++alarms.n;
    alarms.k += o.adopted ? 1 : 0;
    sigmas.push_back(o.one_step_stddev);
  }
  const double sigma_tau = Mean(sigmas);
  std::printf(
      "  null logs (seeds 50000..%d): adopted %s = %s, 95%% CI %s; %d failed; one-step "
      "σ_τ %.1f ms\n",
      50000 + nulls - 1, alarms.Text().c_str(), alarms.Percent().c_str(), alarms.Interval().c_str(),
      failed, sigma_tau * 1e3);
  const double critical = ChiSquare1Critical(defaults.alpha);
  TextTable table(
      {"τ [ms]", "τ/σ_τ", "logs", "adopted", "rate", "theory", "mean τ̂ [ms]", "|τ̂ − τ| ≤ 2σ"});
  nlohmann::ordered_json sizes = nlohmann::ordered_json::array();
  for (size_t k = 0; k < taus.size(); ++k) {
    const double tau = taus[k];
    std::vector<Outcome> logs(per_size);
    ParallelFor(per_size, kThreads, [&](int i) { logs[i] = run(tau, 60000 + 1000 * k + i); });
    Proportion detected, covered;
    std::vector<double> values;
    for (const Outcome& o : logs) {
      if (!o.ok) continue;
      ++detected.n;
      detected.k += o.adopted ? 1 : 0;
      if (o.adopted) {
        ++covered.n;
        covered.k += std::abs(o.value - tau) <= 2.0 * o.stddev ? 1 : 0;
        values.push_back(o.value);
      }
    }
    const double theory = NoncentralChiSquare1Tail(critical, tau * tau / (sigma_tau * sigma_tau));
    table.AddRow({Format("%.0f", tau * 1e3), Format("%.1f", tau / sigma_tau),
                  Format("%d", detected.n), detected.Text(), detected.Percent(),
                  Format("%.1f%%", 100.0 * theory),
                  values.empty() ? "-" : Format("%.1f", Mean(values) * 1e3),
                  covered.n > 0 ? covered.Text() : "-"});
    sizes.push_back({{"tau_s", tau},
                     {"detected", detected.Json()},
                     {"theoretical_power", theory},
                     {"mean_estimate_s", values.empty() ? NAN : Mean(values)},
                     {"within_2_sigma", covered.Json()}});
  }
  table.Print();
  std::printf("  (%.1f s)\n", watch.Seconds());
  return {{"false_alarms", alarms.Json()}, {"failed", failed}, {"sigma_tau_s", sigma_tau},
          {"alpha", defaults.alpha},       {"power", sizes},   {"wall_seconds", watch.Seconds()}};
}

}  // namespace

nlohmann::ordered_json RunDiagnoseBench(bool quick, int seeds) {
  const Stopwatch watch;
  const int intervals = quick ? 1000 : 2000;
  std::printf(
      "\n=== diagnose: calib diagnose on simulated laser logs (%s mode, %d intervals) ===\n",
      quick ? "quick" : "full", intervals);
  nlohmann::ordered_json j;
  j["mode"] = quick ? "quick" : "full";
  j["intervals"] = intervals;
  j["false_alarms"] = RunFalseAlarms(quick, seeds, intervals);
  std::fflush(stdout);
  const std::vector<PowerScenario> scenarios = {
      {LaserEffect::kTimeOffset, PiecewiseRegime(intervals), 10000,
       [](double g, LaserEffects* e) { e->time_offset_s = g; }},
      {LaserEffect::kTimeOffset, SmoothRegime(intervals), 30000,
       [](double g, LaserEffects* e) { e->time_offset_s = g; }},
      {LaserEffect::kLateralSlip, ForwardRegime(intervals), 20000,
       [](double g, LaserEffects* e) { e->lateral_slip_s = g; }},
  };
  nlohmann::ordered_json power = nlohmann::ordered_json::array();
  for (const PowerScenario& scenario : scenarios) {
    power.push_back(RunPower(scenario, quick, seeds, intervals));
    std::fflush(stdout);
  }
  j["power"] = power;
  j["power_skipped"] = "speed_dependent_radius: not modelled by the simulator";
  j["bearing_time_offset"] = RunBearingTimeOffset(quick, seeds);
  j["wall_seconds"] = watch.Seconds();
  std::printf("diagnose section: %.1f s\n", watch.Seconds());
  return j;
}

}  // namespace calib::bench
