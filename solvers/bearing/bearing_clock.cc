#include <calib/core/se2.h>
#include <calib/solvers/bearing/bearing_clock.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace calib {
namespace {

// A step is counted by the bearings when one period's change stands this many σ of a step
// (σβ·√2) clear of the noise and the ratio lies within this of a whole number of periods.
constexpr double kCountedSigmas = 4.0;
constexpr double kWholeTolerance = 0.3;
constexpr double kRateChange = 0.1;
constexpr int kMaxPeriods = 4;
constexpr int kMinSegment = 5;        // Bearings of a run to enter the slope.
constexpr int kMinCountedSteps = 20;  // Over the log, to fit P at all.
constexpr int kEvidence = 2;          // Held or skipped samples that show the clock.
// Skipped samples counted by the bearings show the clock only when noise alone would make that
// many this rarely: a counted one-period step reads as two when its noise reaches 0.7 of the
// change, which over thousands of counted steps happens a few times (10 000 bearings at 1°
// showed 2 and adopted a clock 290 ppm off).
constexpr double kFalseSkipLevel = 1e-3;
// Held repeats on this share of the rows: the logger outpaces the sensor and picks up every
// sample, so consecutive rows (repeats dropped) are consecutive samples.
constexpr double kEverySampleShare = 0.1;

// Periods between rows k − 1 and k by the bearings' step (0: not counted); the step's predicted
// change of one period in `change`.
int CountedPeriods(const BearingClockRun& run, size_t k, double step_s, double sigma_rad,
                   double* change_rad) {
  if (!run.inlier[k - 1] || !run.inlier[k]) return 0;
  // The rate must hold over the step (within kRateChange at its ends) for g·P to predict it.
  const double g0 = run.rates_rad_per_s[k - 1], g1 = run.rates_rad_per_s[k];
  if (!(std::abs(g1 - g0) <= kRateChange * 0.5 * std::abs(g0 + g1))) return 0;
  const double change = 0.5 * (g0 + g1) * step_s;
  *change_rad = change;
  if (!(std::abs(change) > kCountedSigmas * sigma_rad * std::sqrt(2.0))) return 0;
  const double ratio = WrapAngle(run.bearings_rad[k] - run.bearings_rad[k - 1]) / change;
  const double whole = std::round(ratio);
  if (whole < 1.0 || whole > kMaxPeriods || std::abs(ratio - whole) > kWholeTolerance) return 0;
  return static_cast<int>(whole);
}

// The chance that noise alone lifts a counted step by one period or more: its noise (σβ·√2)
// beyond (1 − kWholeTolerance) of one period's change.
double FalseSkipChance(double change_rad, double sigma_rad) {
  return 0.5 * std::erfc((1.0 - kWholeTolerance) * std::abs(change_rad) / (2.0 * sigma_rad));
}

// P(X ≥ m) for X ~ Poisson(λ).
double PoissonTail(double lambda, int m) {
  double term = std::exp(-lambda), below = 0.0;
  for (int j = 0; j < m; ++j) {
    below += term;
    term *= lambda / (j + 1);
  }
  return std::max(0.0, 1.0 - below);
}

double MedianStampStep(const std::vector<BearingClockRun>& runs) {
  std::vector<double> steps;
  for (const BearingClockRun& run : runs) {
    for (size_t k = 1; k < run.stamps_s.size(); ++k) {
      const double step = run.stamps_s[k] - run.stamps_s[k - 1];
      if (step > 0.0) steps.push_back(step);
    }
  }
  if (steps.empty()) return 0.0;
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  return steps[steps.size() / 2];
}

// Pooled within-run sums of the stamps against the counted indices.
struct SlopeSums {
  double nn = 0.0, ns = 0.0, ss = 0.0;
  int points = 0, segments = 0;
  void Add(const std::vector<double>& n, const std::vector<double>& s) {
    if (static_cast<int>(n.size()) < kMinSegment + 1) return;
    double mn = 0.0, ms = 0.0;
    for (size_t k = 0; k < n.size(); ++k) mn += n[k] / n.size(), ms += s[k] / n.size();
    for (size_t k = 0; k < n.size(); ++k) {
      nn += (n[k] - mn) * (n[k] - mn), ns += (n[k] - mn) * (s[k] - ms),
          ss += (s[k] - ms) * (s[k] - ms);
    }
    points += static_cast<int>(n.size()), ++segments;
  }
};

}  // namespace

BearingClockEstimate EstimateBearingClock(const std::vector<BearingClockRun>& runs,
                                          double sigma_rad, int held) {
  BearingClockEstimate out;
  out.stamp_step_s = MedianStampStep(runs);
  out.clocks.assign(runs.size(), SampleClock());
  if (!(out.stamp_step_s > 0.0) || !(sigma_rad > 0.0)) return out;
  // Counted indices per run (stamp steps where the bearings cannot count) and the slope sums
  // over the stretches the bearings counted.
  int rows = held;
  for (const BearingClockRun& run : runs) rows += static_cast<int>(run.stamps_s.size());
  const bool every_sample = held >= kEverySampleShare * rows;
  SlopeSums sums;
  double expected_false_skips = 0.0;  // Of noise alone, over the counted steps.
  std::vector<std::vector<double>> counted(runs.size());
  for (size_t i = 0; i < runs.size(); ++i) {
    const BearingClockRun& run = runs[i];
    std::vector<double>& n = counted[i];
    for (size_t k = 0; k < run.stamps_s.size(); ++k) {
      if (k == 0) {
        n.push_back(0.0);
        continue;
      }
      // Where the bearings cannot count: one sample per row when the logger picks up every one
      // (a stamp step beyond 1.5 of the usual is a gap), else the stamps' whole steps.
      const double stamp_ratio = (run.stamps_s[k] - run.stamps_s[k - 1]) / out.stamp_step_s;
      const double stamp_periods =
          every_sample && stamp_ratio < 1.5 ? 1.0 : std::max(1.0, std::round(stamp_ratio));
      double change = 0.0;
      const int periods = CountedPeriods(run, k, out.stamp_step_s, sigma_rad, &change);
      n.push_back(n.back() + (periods > 0 ? periods : stamp_periods));
      if (periods == 0) continue;
      ++out.counted_steps;
      out.skipped_samples += std::max(0, periods - static_cast<int>(stamp_periods));
      expected_false_skips += FalseSkipChance(change, sigma_rad);
    }
    sums.Add(n, run.stamps_s);
  }
  out.held_samples = held;
  const bool skips_show = out.skipped_samples >= kEvidence &&
                          PoissonTail(expected_false_skips, out.skipped_samples) < kFalseSkipLevel;
  out.free_running = held >= kEvidence || skips_show;
  out.period_determined = every_sample || skips_show;
  if (out.counted_steps < kMinCountedSteps || !(sums.nn > 0.0)) return out;
  out.tested = true;
  out.period_s = sums.ns / sums.nn;
  const int dof = sums.points - sums.segments - 1;
  const double lag_var = dof > 0 ? std::max(0.0, sums.ss - out.period_s * sums.ns) / dof : 0.0;
  out.period_stddev_s = std::sqrt(lag_var / sums.nn);
  for (size_t i = 0; i < runs.size(); ++i) {
    if (runs[i].stamps_s.empty()) continue;
    // The phase: the lower envelope of s − P·n (no sample is picked up before it is taken).
    double t0 = INFINITY;
    for (size_t k = 0; k < counted[i].size(); ++k) {
      t0 = std::min(t0, runs[i].stamps_s[k] - out.period_s * counted[i][k]);
    }
    out.clocks[i].t0_s = t0 - 1e-9 * out.period_s;
    out.clocks[i].period_s = out.period_s;
  }
  return out;
}

std::vector<double> BearingClockTimes(const std::vector<double>& stamps_s,
                                      const SampleClock& clock) {
  std::vector<double> times = ClockIndicesFromStamps(stamps_s, clock);
  for (double& t : times) t = clock.Time(t);
  return times;
}

bool IsHeldBearing(const BearingRun& run, size_t k) {
  return k > 0 && k < run.bearings.size() &&
         run.bearings[k].bearing_rad == run.bearings[k - 1].bearing_rad;
}

BearingLog DropHeldBearings(const BearingLog& log, int* dropped) {
  BearingLog out;
  out.source = log.source;
  out.meta = log.meta;
  out.stream_timing = log.stream_timing;
  *dropped = 0;
  for (const BearingRun& run : log.runs) {
    BearingRun kept{run.id, run.odometry, {}};
    for (size_t k = 0; k < run.bearings.size(); ++k) {
      if (IsHeldBearing(run, k)) {
        ++*dropped;
        continue;
      }
      kept.bearings.push_back(run.bearings[k]);
    }
    out.runs.push_back(std::move(kept));
  }
  return out;
}

}  // namespace calib
