#include <calib/core/bearing/bearing_simulator.h>
#include <calib/solvers/bearing/bearing_diagnosis.h>
#include <calib/solvers/stats/score_test.h>

#include <cstdio>
#include <map>

#include "benchmarks/bench_diagnose_internal.h"

namespace calib::bench::diagnose {
namespace {

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

}  // namespace

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

// --- 2. Power against effect size ----------------------------------------------------------

namespace {

// The pilot: σ_γ of the one-step estimate on logs without the effect.
struct Pilot {
  uint64_t seed_base = 0;
  int logs = 0;
  double sigma = 0.0;  // Mean reported one-step σ_γ over the logs where the effect is testable.
};

Pilot RunPilot(const PowerScenario& scenario, int logs, int intervals) {
  const int e = static_cast<int>(scenario.effect);
  Pilot pilot;
  pilot.seed_base = scenario.seed_base + 900;
  pilot.logs = logs;
  const std::vector<LogOutcome> outcomes = RunLogs(logs, [&](int i) {
    return MakeLog(scenario.regime, LaserEffects(), 0.0, pilot.seed_base + i, intervals);
  });
  std::vector<double> sds;
  for (const LogOutcome& log : outcomes) {
    if (log.ok && log.candidates[e].testable) sds.push_back(log.candidates[e].one_step_stddev);
  }
  pilot.sigma = Mean(sds);
  return pilot;
}

// What the logs of one effect size say about the scenario's effect.
struct SizeTally {
  std::vector<double> sds, estimates, one_steps;  // Reported σ_γ, adopted values, one-steps.
  int failed = 0;
  int m = 0;  // The number of testable candidates most logs have.
};

SizeTally TallySize(const std::vector<LogOutcome>& logs, int e) {
  SizeTally t;
  std::map<int, int> m_count;
  for (const LogOutcome& log : logs) {
    if (!log.ok) {
      ++t.failed;
      continue;
    }
    ++m_count[log.testable];
    const CandidateOutcome& c = log.candidates[e];
    if (c.testable) {
      t.sds.push_back(c.one_step_stddev);
      t.one_steps.push_back(c.one_step);
    }
    if (c.adopted) t.estimates.push_back(c.value);
  }
  int m_logs = -1;
  for (const auto& [count, k] : m_count) {
    if (k > m_logs) t.m = count, m_logs = k;
  }
  return t;
}

// Rates over the logs that ran: score statistic > c, Holm, adopted, another effect adopted.
struct SizeRates {
  Proportion reject, holm, adopted, others;
};

SizeRates RatesAtSize(const std::vector<LogOutcome>& logs, int e, double critical) {
  SizeRates r;
  for (const LogOutcome& log : logs) {
    if (!log.ok) continue;
    const CandidateOutcome& cand = log.candidates[e];
    ++r.reject.n;
    ++r.holm.n;
    ++r.adopted.n;
    ++r.others.n;
    r.reject.k += cand.testable && cand.statistic > critical;
    r.holm.k += cand.holm;
    r.adopted.k += cand.adopted;
    r.others.k += static_cast<int>(log.adopted.size()) > (cand.adopted ? 1 : 0);
  }
  return r;
}

// One effect size: its logs, a row of `table`, and its JSON.
nlohmann::ordered_json RunPowerSize(const PowerScenario& scenario, double gamma, double multiple,
                                    uint64_t base, int per_size, int intervals, TextTable* table) {
  const int e = static_cast<int>(scenario.effect);
  LaserEffects effects;
  scenario.set(gamma, &effects);
  const std::vector<LogOutcome> logs = RunLogs(
      per_size, [&](int i) { return MakeLog(scenario.regime, effects, 0.0, base + i, intervals); });
  const SizeTally t = TallySize(logs, e);
  const double level = LaserDiagnosisOptions().alpha / std::max(t.m, 1);
  const double c = ChiSquare1Critical(level);
  const double sd = Mean(t.sds);
  const double lambda = std::pow(gamma / sd, 2);
  const double theory = NoncentralChiSquare1Tail(c, lambda);
  const SizeRates r = RatesAtSize(logs, e, c);
  std::string estimate = "-";
  if (t.estimates.size() == 1) estimate = Format("%.2f", t.estimates[0] * 1e3);
  if (t.estimates.size() > 1) {
    estimate = Format("%.2f +- %.2f", Mean(t.estimates) * 1e3, StdDev(t.estimates) * 1e3);
  }
  const std::string one_step =
      Format("%.2f +- %.2f", Mean(t.one_steps) * 1e3, StdDev(t.one_steps) * 1e3);
  table->AddRow({Format("%.3g", gamma * 1e3), Format("%.2f", gamma / sd), Format("%.2f", sd * 1e3),
                 Format("%.2f", lambda), std::to_string(t.m), Format("%.1f%%", 100.0 * theory),
                 r.reject.Percent(), r.reject.Interval(), r.holm.Percent(), r.adopted.Percent(),
                 r.adopted.Interval(), r.others.Text(), one_step, estimate,
                 Format("%llu..%llu", static_cast<unsigned long long>(base),
                        static_cast<unsigned long long>(base + per_size - 1))});
  return {{"gamma", gamma},
          {"multiple_of_pilot_sigma", multiple},
          {"seeds", {base, base + per_size - 1}},
          {"logs", per_size},
          {"failed", t.failed},
          {"sigma_gamma_mean", sd},
          {"gamma_over_sigma", gamma / sd},
          {"lambda", lambda},
          {"testable_candidates", t.m},
          {"holm_first_level", level},
          {"critical_value", c},
          {"theoretical_power", theory},
          {"score_rejection", r.reject.Json()},
          {"holm_significant", r.holm.Json()},
          {"detection", r.adopted.Json()},
          {"other_effect_adopted", r.others.Json()},
          {"one_step_mean", Mean(t.one_steps)},
          {"one_step_stddev_empirical", StdDev(t.one_steps)},
          {"adopted_value_mean", t.estimates.empty() ? NAN : Mean(t.estimates)},
          {"adopted_value_stddev", StdDev(t.estimates)}};
}

}  // namespace

nlohmann::ordered_json RunPower(const PowerScenario& scenario, bool quick, int seeds,
                                int intervals) {
  const std::string name = LaserEffectName(scenario.effect);
  const int per_size = seeds > 0 ? seeds : (quick ? 8 : 40);
  const std::vector<double> multiples = {1.0, 2.0, 3.0, 4.0, 6.0};
  const LaserDiagnosisOptions defaults;
  const Stopwatch watch;

  const Pilot pilot = RunPilot(scenario, quick ? 2 : 4, intervals);
  std::printf("\n== diagnose 2: power for %s (%s) ==\n", name.c_str(),
              scenario.regime.name.c_str());
  std::printf("Simulation: %s; %d intervals; no outliers.\n", scenario.regime.description.c_str(),
              intervals);
  std::printf(
      "Pilot: %d logs without the effect (seeds %llu..%llu): one-step sigma_gamma = %.3g ms.\n",
      pilot.logs, static_cast<unsigned long long>(pilot.seed_base),
      static_cast<unsigned long long>(pilot.seed_base + pilot.logs - 1), pilot.sigma * 1e3);
  if (!(pilot.sigma > 0.0)) {
    std::printf("The pilot found no testable %s; skipped.\n", name.c_str());
    return {{"effect", name}, {"skipped", "not testable in the pilot"}};
  }

  TextTable table({"gamma ms", "gamma/sd", "sd ms", "lambda", "m", "theory", "score rej", "95% CI",
                   "Holm", "adopted", "95% CI", "others", "one-step ms", "estimate ms", "seeds"});
  nlohmann::ordered_json sizes = nlohmann::ordered_json::array();
  for (size_t s = 0; s < multiples.size(); ++s) {
    sizes.push_back(RunPowerSize(scenario, Round2(multiples[s] * pilot.sigma), multiples[s],
                                 scenario.seed_base + 100 * s, per_size, intervals, &table));
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
           {{"logs", pilot.logs},
            {"seeds", {pilot.seed_base, pilot.seed_base + pilot.logs - 1}},
            {"sigma_gamma", pilot.sigma}}},
          {"alpha", defaults.alpha},
          {"sizes", sizes},
          {"wall_seconds", watch.Seconds()}};
}

namespace {

// The diagnosis of one simulated weaving-run log (data/diagnose's bearing recipe) with offset τ.
struct BearingOutcome {
  bool ok = false;
  bool adopted = false;
  double value = 0.0, stddev = 0.0, one_step_stddev = 0.0;
};

BearingOutcome DiagnoseBearingLog(double tau, uint64_t seed) {
  BearingSimOptions o;
  o.seed = seed;
  o.encoder_rate_hz = 5.0;
  o.bearing_rate_hz = 2.0;
  o.bearing_noise_rad = M_PI / 180.0;
  o.initial_distance_run = 1;
  o.time_offset_s = tau;
  o.runs = {WeavingRun()};
  BearingOutcome out;
  const StatusOr<BearingDiagnosis> d = DiagnoseBearing(SimulateBearingLog(o));
  if (!d.ok()) return out;
  out.ok = true;
  const BearingFinding& f = d->findings[0];
  out.adopted = f.significant;
  out.value = f.value;
  out.stddev = f.stddev;
  out.one_step_stddev = f.one_step_stddev(0);
  return out;
}

std::vector<BearingOutcome> DiagnoseBearingLogs(int n, double tau, uint64_t seed_base) {
  std::vector<BearingOutcome> logs(n);
  ParallelFor(n, kThreads, [&](int i) { logs[i] = DiagnoseBearingLog(tau, seed_base + i); });
  return logs;
}

// The null logs (τ = 0): false alarms, and σ_τ the mean one-step standard deviation.
struct BearingNull {
  Proportion alarms;
  int failed = 0;
  double sigma_tau = 0.0;
};

BearingNull SummarizeNull(const std::vector<BearingOutcome>& null) {
  BearingNull out;
  std::vector<double> sigmas;
  for (const BearingOutcome& o : null) {
    if (!o.ok) {
      ++out.failed;
      continue;
    }
    ++out.alarms.n;
    out.alarms.k += o.adopted ? 1 : 0;
    sigmas.push_back(o.one_step_stddev);
  }
  out.sigma_tau = Mean(sigmas);
  return out;
}

// One offset τ: the detection rate next to the theory, a row of `table`, and its JSON.
nlohmann::ordered_json SummarizeBearingSize(const std::vector<BearingOutcome>& logs, double tau,
                                            double sigma_tau, double critical, TextTable* table) {
  Proportion detected, covered;
  std::vector<double> values;
  for (const BearingOutcome& o : logs) {
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
  table->AddRow({Format("%.0f", tau * 1e3), Format("%.1f", tau / sigma_tau),
                 Format("%d", detected.n), detected.Text(), detected.Percent(),
                 Format("%.1f%%", 100.0 * theory),
                 values.empty() ? "-" : Format("%.1f", Mean(values) * 1e3),
                 covered.n > 0 ? covered.Text() : "-"});
  return {{"tau_s", tau},
          {"detected", detected.Json()},
          {"theoretical_power", theory},
          {"mean_estimate_s", values.empty() ? NAN : Mean(values)},
          {"within_2_sigma", covered.Json()}};
}

}  // namespace

// The bearing problem's one candidate, time_offset, on the weaving run of data/diagnose
// (WeavingRun: 300 s, 2 Hz bearings, σβ = 1°, K = 1e-3): false alarms on null logs, and the
// detection rate against τ next to the score test's power χ²₁(λ = τ²/σ_τ²) at the level, σ_τ the
// mean one-step standard deviation of the null logs.
nlohmann::ordered_json RunBearingTimeOffset(bool quick, int seeds) {
  const int nulls = seeds > 0 ? seeds : (quick ? 4 : 100);
  const int per_size = seeds > 0 ? seeds : (quick ? 2 : 30);
  const std::vector<double> taus = {0.05, 0.1, 0.15};
  const BearingDiagnosisOptions defaults;
  std::printf(
      "\n== diagnose 3: bearing time_offset (weaving run, 300 s, 2 Hz bearings, σβ 1°; "
      "alpha %.3g) ==\n",
      defaults.alpha);
  const Stopwatch watch;
  const BearingNull null = SummarizeNull(DiagnoseBearingLogs(nulls, 0.0, 50000));
  std::printf(
      "  null logs (seeds 50000..%d): adopted %s = %s, 95%% CI %s; %d failed; one-step "
      "σ_τ %.1f ms\n",
      50000 + nulls - 1, null.alarms.Text().c_str(), null.alarms.Percent().c_str(),
      null.alarms.Interval().c_str(), null.failed, null.sigma_tau * 1e3);
  const double critical = ChiSquare1Critical(defaults.alpha);
  TextTable table(
      {"τ [ms]", "τ/σ_τ", "logs", "adopted", "rate", "theory", "mean τ̂ [ms]", "|τ̂ − τ| ≤ 2σ"});
  nlohmann::ordered_json sizes = nlohmann::ordered_json::array();
  for (size_t k = 0; k < taus.size(); ++k) {
    const std::vector<BearingOutcome> logs =
        DiagnoseBearingLogs(per_size, taus[k], 60000 + 1000 * k);
    sizes.push_back(SummarizeBearingSize(logs, taus[k], null.sigma_tau, critical, &table));
  }
  table.Print();
  std::printf("  (%.1f s)\n", watch.Seconds());
  return {{"false_alarms", null.alarms.Json()},
          {"failed", null.failed},
          {"sigma_tau_s", null.sigma_tau},
          {"alpha", defaults.alpha},
          {"power", sizes},
          {"wall_seconds", watch.Seconds()}};
}

}  // namespace calib::bench::diagnose
