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

}  // namespace calib::bench::diagnose
