#ifndef CALIB_BENCHMARKS_BENCH_DIAGNOSE_H_
#define CALIB_BENCHMARKS_BENCH_DIAGNOSE_H_

#include <nlohmann/json.hpp>

// `calib diagnose` (DiagnoseLaser, default options) on simulated laser logs. Prints its tables
// on stdout, with the seeds and simulation settings beside each, and returns every number as
// JSON:
//   1. False alarms: clean logs (no effect), half without and half with 5 % slip outliers, each
//      half alternating the smooth (`calib simulate` defaults) and the piecewise-constant speed
//      regime of data/diagnose's controls. The fraction of logs on which any effect is adopted
//      (Wilson 95 % interval) against the target (nothing adopted on ≥ 95 %), and per
//      candidate how often it is testable, how often its score test alone is significant at
//      the family level α, how often it passes Holm's step-down, and how often it is adopted.
//   2. Power: time_offset and lateral_slip in the regimes of data/diagnose where they are
//      concealed, at effect sizes that are multiples of the one-step σ_γ of a pilot run. The
//      detection rate (effect adopted) and the score test's rejection rate at the first Holm
//      level, against the score test's theoretical power P(χ²₁(λ) > c), λ = (γ/σ_γ)², c the
//      χ²₁ critical value at α/m (m testable candidates), σ_γ the reported standard deviation
//      of the one-step estimate averaged over the logs.
// (The speed-dependent radius is not modelled by the simulator and is left out.)
namespace calib::bench {

// seeds = 0: 100 + 100 clean logs and 40 logs per effect size (10 + 10 and 8 with `quick`,
// which also halves the intervals per log); otherwise `seeds` logs per group and per size.
nlohmann::ordered_json RunDiagnoseBench(bool quick, int seeds);

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_DIAGNOSE_H_
