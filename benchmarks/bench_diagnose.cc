#include "benchmarks/bench_diagnose.h"

#include <cstdio>
#include <map>

#include "benchmarks/bench_diagnose_internal.h"

namespace calib::bench {
namespace diagnose {

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

namespace {

// --- 1. False alarms on clean logs ---------------------------------------------------------

struct CleanGroup {
  std::string name;
  Regime regime;
  double outliers = 0.0;
  uint64_t seed_base = 0;
  std::vector<LogOutcome> logs;
};

// Per candidate, pooled over the groups of clean logs: how often it is testable, significant
// alone, passes Holm and is adopted.
nlohmann::ordered_json CandidateTable(const std::vector<CleanGroup>& groups, int logs,
                                      double alpha) {
  const LaserDiagnosisOptions defaults;
  std::printf(
      "\nPer candidate over all %d clean logs (the finding's last score test; 'alone': p <= "
      "alpha = %.3g, i.e. significant at the family level without the multiplicity correction; "
      "'Holm': passed the step-down; per group S, P, S+o, P+o):\n",
      logs, alpha);
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

  return candidates_json;
}

// Simulates and diagnoses the clean logs of each group (their first `n` seeds: `smooth_n` for the
// even groups, `piecewise_n` for the odd ones).
void RunCleanGroups(std::vector<CleanGroup>* groups, int smooth_n, int piecewise_n, int intervals) {
  for (size_t g = 0; g < groups->size(); ++g) {
    CleanGroup& group = (*groups)[g];
    const int n = g % 2 == 0 ? smooth_n : piecewise_n;
    std::printf("  %-24s %3d logs, seeds %llu..%llu: %s\n", group.name.c_str(), n,
                static_cast<unsigned long long>(group.seed_base),
                static_cast<unsigned long long>(group.seed_base + n - 1),
                group.regime.description.c_str());
    group.logs = RunLogs(n, [&](int i) {
      return MakeLog(group.regime, LaserEffects(), group.outliers, group.seed_base + i, intervals);
    });
  }
}

// Any adoption on the clean logs, per group and pooled.
struct CleanAlarms {
  Proportion all, without, with;  // All logs; the groups without and with outliers.
  std::vector<double> all_seconds;
  std::map<std::string, int> adopted_names;
  nlohmann::ordered_json alarms = nlohmann::ordered_json::array();  // Which log adopted what.
  nlohmann::ordered_json groups = nlohmann::ordered_json::array();
  int failed = 0;
};

// Counts the adoptions of `groups` into `out` and a row of `table` per group.
void CountAlarms(const std::vector<CleanGroup>& groups, int intervals, TextTable* table,
                 CleanAlarms* out) {
  for (const CleanGroup& group : groups) {
    Proportion p;
    int failed = 0;
    std::vector<double> secs;
    for (size_t i = 0; i < group.logs.size(); ++i) {
      const LogOutcome& log = group.logs[i];
      secs.push_back(log.seconds);
      out->all_seconds.push_back(log.seconds);
      if (!log.ok) {
        ++failed;
        continue;
      }
      ++p.n;
      if (!log.adopted.empty()) {
        ++p.k;
        for (const std::string& name : log.adopted) ++out->adopted_names[name];
        out->alarms.push_back(
            {{"group", group.name}, {"seed", group.seed_base + i}, {"adopted", log.adopted}});
      }
    }
    out->failed += failed;
    out->all.k += p.k;
    out->all.n += p.n;
    Proportion& half = group.outliers > 0 ? out->with : out->without;
    half.k += p.k;
    half.n += p.n;
    table->AddRow({group.name, std::to_string(p.n), std::to_string(p.k), p.Percent(), p.Interval(),
                   Format("%.1f%%", 100.0 * (1.0 - p.rate())), std::to_string(failed),
                   Format("%.2f", Median(secs))});
    out->groups.push_back({{"name", group.name},
                           {"simulation", SimJson(group.regime, intervals, group.outliers)},
                           {"seeds", {group.seed_base, group.seed_base + group.logs.size() - 1}},
                           {"false_alarm", p.Json()},
                           {"failed", failed},
                           {"median_seconds", Median(secs)}});
  }
}

// Prints the adoption table, per group and pooled, and the target; returns the counts.
CleanAlarms TabulateAlarms(const std::vector<CleanGroup>& groups, int intervals, double seconds) {
  TextTable table(
      {"logs", "n", "adopted any", "rate", "95% CI", "nothing adopted", "failed", "median s/log"});
  CleanAlarms a;
  CountAlarms(groups, intervals, &table, &a);
  table.AddRule();
  const auto pooled_row = [&](const std::string& name, const Proportion& p) {
    table.AddRow({name, std::to_string(p.n), std::to_string(p.k), p.Percent(), p.Interval(),
                  Format("%.1f%%", 100.0 * (1.0 - p.rate())), "", ""});
  };
  pooled_row("without outliers", a.without);
  pooled_row("with 5% outliers", a.with);
  pooled_row("all clean logs", a.all);
  table.Print();
  std::printf(
      "Target (nothing adopted on >= 95%% of clean logs): %s (%.1f%% clean; the false-alarm "
      "rate's 95%% upper bound %.1f%% %s 5%%). %d failed runs. %.1f s wall.\n",
      1.0 - a.all.rate() >= 0.95 ? "MET" : "NOT MET", 100.0 * (1.0 - a.all.rate()),
      100.0 * a.all.upper(), a.all.upper() < 0.05 ? "<" : ">=", a.failed, seconds);
  if (!a.adopted_names.empty()) {
    std::printf("Adopted on clean logs:");
    for (const auto& [name, count] : a.adopted_names) std::printf(" %s x%d", name.c_str(), count);
    std::printf("\n");
  }
  return a;
}

nlohmann::ordered_json RunFalseAlarms(bool quick, int seeds, int intervals) {
  const int per_half = seeds > 0 ? seeds : (quick ? 10 : 100);
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
  RunCleanGroups(&groups, (per_half + 1) / 2, per_half / 2, intervals);
  const double seconds = watch.Seconds();
  const CleanAlarms a = TabulateAlarms(groups, intervals, seconds);
  const nlohmann::ordered_json candidates_json = CandidateTable(groups, a.all.n, defaults.alpha);

  nlohmann::ordered_json j;
  j["intervals"] = intervals;
  j["logs_without_outliers"] = per_half;
  j["logs_with_outliers"] = per_half;
  j["alpha"] = defaults.alpha;
  j["groups"] = a.groups;
  j["false_alarm_without_outliers"] = a.without.Json();
  j["false_alarm_with_outliers"] = a.with.Json();
  j["false_alarm"] = a.all.Json();
  j["nothing_adopted_rate"] = 1.0 - a.all.rate();
  j["target_nothing_adopted"] = 0.95;
  j["target_met"] = 1.0 - a.all.rate() >= 0.95;
  j["target_met_at_95_confidence"] = a.all.upper() < 0.05;
  j["alarms"] = a.alarms;
  j["failed"] = a.failed;
  j["candidates"] = candidates_json;
  j["median_seconds_per_log"] = Median(a.all_seconds);
  j["wall_seconds"] = seconds;
  return j;
}

}  // namespace
}  // namespace diagnose

nlohmann::ordered_json RunDiagnoseBench(bool quick, int seeds) {
  using namespace diagnose;  // NOLINT: the section's pieces.
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
