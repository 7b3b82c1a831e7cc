#include <calib/core/timing/stamp_timing.h>
#include <calib/core/timing/stamp_timing_internal.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace calib {
namespace {

using timing_internal::Median;

constexpr int kWindow = 40;                  // Samples per local grid fit.
constexpr double kGapPeriods = 5.0;          // A longer interval is a gap.
constexpr double kMultipleTolerance = 0.25;  // |Δ/P − k| within this is "near k·P".
constexpr int kStepWindow = 8;               // Steps per steady-window test.
constexpr double kStepTolerance = 0.15;      // |d/u − k| within this is a whole multiple.
constexpr double kUnitSpread = 0.1;          // Largest over smallest step at the usual multiple.

// The base period: the largest m/n (m the median interval, n = 1..6) such that at least 80 % of
// the intervals lie near a whole multiple k ≥ 1 of it, refined as the median of Δ/k over them.
double BasePeriod(const std::vector<double>& intervals) {
  const double m = Median(intervals);
  for (int n = 1; n <= 6; ++n) {
    const double period = m / n;
    std::vector<double> per_step;
    for (const double d : intervals) {
      const double k = std::round(d / period);
      if (k >= 1 && (k > kGapPeriods || std::abs(d / period - k) <= kMultipleTolerance)) {
        if (k <= kGapPeriods) per_step.push_back(d / k);
      }
    }
    if (per_step.size() >= 0.8 * intervals.size() && !per_step.empty()) return Median(per_step);
  }
  return m;
}

// Robust line t = a + P·N over one block: P the median of slopes between samples half a block
// apart, a the median intercept. Appends the residuals (scaled for the two fitted parameters)
// and the interval deviations δ_k = Δ_k − n_k·P.
void FitBlock(const double* t, const double* index, int w, std::vector<double>* residuals,
              std::vector<std::pair<double, bool>>* deviations) {
  const int h = std::max(1, w / 2);
  std::vector<double> slopes;
  for (int i = 0; i + h < w; ++i) slopes.push_back((t[i + h] - t[i]) / (index[i + h] - index[i]));
  const double period = Median(slopes);
  std::vector<double> intercepts(w);
  for (int i = 0; i < w; ++i) intercepts[i] = t[i] - period * index[i];
  const double t0 = Median(intercepts);
  const double dof = std::sqrt(static_cast<double>(w) / (w - 2));
  for (int i = 0; i < w; ++i) residuals->push_back((intercepts[i] - t0) * dof);
  for (int i = 0; i + 1 < w; ++i) {
    // The first deviation of a block has no predecessor in it.
    deviations->emplace_back(t[i + 1] - t[i] - (index[i + 1] - index[i]) * period, i > 0);
  }
}

// Lag-1 covariance and correlation of the deviations (clipped at 4 robust σ), pairs within
// blocks only.
void IntervalCorrelation(const std::vector<std::pair<double, bool>>& deviations,
                         StreamTiming* timing) {
  std::vector<double> magnitude;
  for (const auto& d : deviations) magnitude.push_back(std::abs(d.first));
  if (magnitude.size() < 8) return;
  const double clip = 4.0 * 1.4826 * Median(magnitude) + 1e-300;
  const auto clipped = [&](double v) { return std::clamp(v, -clip, clip); };
  double mean = 0.0;
  for (const auto& d : deviations) mean += clipped(d.first);
  mean /= deviations.size();
  double variance = 0.0, covariance = 0.0;
  int pairs = 0;
  for (size_t k = 0; k < deviations.size(); ++k) {
    const double a = clipped(deviations[k].first) - mean;
    variance += a * a;
    if (k > 0 && deviations[k].second) {
      covariance += a * (clipped(deviations[k - 1].first) - mean);
      ++pairs;
    }
  }
  variance /= deviations.size();
  if (pairs == 0 || !(variance > 0.0)) return;
  covariance /= pairs;
  timing->interval_correlation = covariance / variance;
  timing->pickup_scatter_s = std::sqrt(std::max(0.0, -covariance));
}

// Period, gaps, multiples, jitter and interval correlation of strictly ordered unique stamps.
void AnalyzeGrid(const std::vector<double>& t, StreamTiming* timing) {
  std::vector<double> intervals;
  for (size_t k = 0; k + 1 < t.size(); ++k) {
    if (t[k + 1] > t[k]) intervals.push_back(t[k + 1] - t[k]);
  }
  timing->intervals = static_cast<int>(intervals.size());
  if (intervals.empty()) return;
  const double period = BasePeriod(intervals);
  timing->period_s = period;
  if (!(period > 0.0)) return;

  std::vector<double> residuals;
  std::vector<std::pair<double, bool>> deviations;
  std::vector<double> index = {0.0};
  int multiples = 0, regular_intervals = 0;
  double span_s = 0.0, span_periods = 0.0;
  size_t segment = 0;  // First sample of the current segment.
  for (size_t k = 0; k + 1 <= t.size(); ++k) {
    const double d = k + 1 < t.size() ? t[k + 1] - t[k] : 0.0;
    const bool end = k + 1 == t.size() || !(d > 0.0) || d > kGapPeriods * period;
    if (k + 1 < t.size() && d > kGapPeriods * period) {
      ++timing->gaps;
      timing->longest_gap_s = std::max(timing->longest_gap_s, d);
    } else if (k + 1 < t.size() && d > 0.0) {
      const double n = std::max(1.0, std::round(d / period));
      ++regular_intervals;
      if (n >= 2 && std::abs(d / period - n) <= kMultipleTolerance) ++multiples;
    }
    if (!end) {
      index.push_back(index.back() + std::max(1.0, std::round(d / period)));
      continue;
    }
    // Fit the segment [segment, k] in blocks of about kWindow samples.
    const int length = static_cast<int>(k + 1 - segment);
    span_s += t[k] - t[segment];
    span_periods += index.back();
    if (length >= 4) {
      const int blocks = std::max(1, length / kWindow);
      for (int b = 0; b < blocks; ++b) {
        // In 64 bits: length · b passes 2^31 in an hour of 100 Hz samples.
        const int lo = static_cast<int>(int64_t{length} * b / blocks);
        const int hi = static_cast<int>(int64_t{length} * (b + 1) / blocks);
        FitBlock(&t[segment + lo], &index[lo], hi - lo, &residuals, &deviations);
      }
    }
    segment = k + 1;
    index = {0.0};
  }
  // The mean period over the segments is far more precise than the median interval.
  if (span_periods > 0.0) timing->period_s = span_s / span_periods;
  if (regular_intervals > 0) {
    timing->multiple_fraction = static_cast<double>(multiples) / regular_intervals;
  }
  for (double& r : residuals) r = std::abs(r);
  if (!residuals.empty()) timing->jitter_s = 1.4826 * Median(residuals);
  IntervalCorrelation(deviations, timing);
}

bool SameValues(const std::vector<double>& values, size_t width, size_t a, size_t b) {
  return std::equal(values.begin() + a * width, values.begin() + (a + 1) * width,
                    values.begin() + b * width);
}

double StepLength(const std::vector<double>& values, size_t width, size_t a, size_t b) {
  double sum = 0.0;
  for (size_t c = 0; c < width; ++c) {
    const double d = values[b * width + c] - values[a * width + c];
    sum += d * d;
  }
  return std::sqrt(sum);
}

// True when every column moves in whole multiples of its smallest non-zero change (encoder
// ticks): then a 0- or 2-step is quantization, not a held or skipped sample.
bool Quantized(const std::vector<double>& values, size_t width, size_t n) {
  for (size_t c = 0; c < width; ++c) {
    double quantum = INFINITY;
    for (size_t k = 0; k + 1 < n; ++k) {
      const double d = std::abs(values[(k + 1) * width + c] - values[k * width + c]);
      if (d > 0.0) quantum = std::min(quantum, d);
    }
    if (!std::isfinite(quantum)) continue;
    int off = 0;
    for (size_t k = 0; k + 1 < n; ++k) {
      const double r = std::abs(values[(k + 1) * width + c] - values[k * width + c]) / quantum;
      if (std::abs(r - std::round(r)) > 1e-6 * std::max(1.0, r)) ++off;
    }
    if (off > 0.01 * n) return false;
  }
  return true;
}

// Held repeats: v_k = v_{k−1}, the neighbours differ, and the step after catches up at least
// 1.5 typical steps (the median non-zero step within ±4).
int CountHeldRepeats(const std::vector<double>& steps) {
  int held = 0;
  for (size_t k = 1; k + 1 < steps.size(); ++k) {
    if (steps[k] != 0.0 || steps[k - 1] == 0.0 || steps[k + 1] == 0.0) continue;
    std::vector<double> near;
    for (size_t j = k > 4 ? k - 4 : 0; j < std::min(steps.size(), k + 5); ++j) {
      if (j != k + 1 && steps[j] > 0.0) near.push_back(steps[j]);
    }
    if (!near.empty() && steps[k + 1] >= 1.5 * Median(near)) ++held;
  }
  return held;
}

// The window's steps at its usual multiple agree to kUnitSpread: the speed was constant, and a
// free-running sensor's samples are then one unit each.
bool ConstantUnit(const double* d, const std::vector<int>& k_of, int mode) {
  double lo = INFINITY, hi = 0.0;
  for (size_t i = 0; i < k_of.size(); ++i) {
    if (k_of[i] != mode) continue;
    lo = std::min(lo, d[i]);
    hi = std::max(hi, d[i]);
  }
  return hi > 0.0 && hi <= (1.0 + kUnitSpread) * lo;
}

// Every run of steps off the window's usual multiple m sits between steps at it, is at most three
// steps long and adds up to within one unit of m per step: a skipped or held sample (with its
// catch-up, or the run a jittery logger makes where its pick-up crosses the sensor's tick) keeps
// the sensor's pace. A change of speed (the simulator's segments switch speeds at once) instead
// starts a new level, which a third or half of a step can fit as multiples of a smaller unit.
bool IsolatedOffSteps(const std::vector<int>& k_of, int mode) {
  const int w = static_cast<int>(k_of.size());
  for (int i = 0; i < w; ++i) {
    if (k_of[i] == mode) continue;
    int end = i, sum = 0;
    while (end < w && k_of[end] != mode) sum += k_of[end++];
    const int length = end - i;
    if (i == 0 || end >= w || length > 3 || std::abs(sum - length * mode) > 1) return false;
    i = end;
  }
  return true;
}

}  // namespace

StepMultiples AnalyzeDisplacementSteps(const std::vector<double>& stamps_s,
                                       const std::vector<double>& step_lengths) {
  (void)stamps_s;
  // Windows overlap by half, so that a skip or hold at one window's edge (which that window
  // cannot tell from a change of speed) lies inside the next; each step is counted once.
  // kind: −1 not in a steady window, 0 at its window's usual multiple, 1 held, 2 other multiple.
  std::vector<int> kind(step_lengths.size(), -1);
  for (size_t b = 0; b + kStepWindow <= step_lengths.size(); b += kStepWindow / 2) {
    std::vector<int> k_of;
    if (!timing_internal::SteadyWindow(&step_lengths[b], kStepWindow, kStepTolerance, &k_of)) {
      continue;
    }
    int counts[5] = {0, 0, 0, 0, 0};
    for (const int k : k_of) ++counts[k];
    const int mode = static_cast<int>(std::max_element(counts + 1, counts + 5) - counts);
    if (!ConstantUnit(&step_lengths[b], k_of, mode) || !IsolatedOffSteps(k_of, mode)) continue;
    for (int i = 0; i < kStepWindow; ++i) {
      const int step_kind = k_of[i] == mode ? 0 : (k_of[i] == 0 ? 1 : 2);
      kind[b + i] = std::max(kind[b + i], step_kind);
    }
  }
  StepMultiples out;
  for (const int k : kind) {
    out.steady_steps += k >= 0;
    out.zero_steps += k == 1;
    out.multi_steps += k == 2;
  }
  const int off_mode = out.zero_steps + out.multi_steps;
  if (out.steady_steps > 0) {
    out.multiple_fraction = static_cast<double>(off_mode) / out.steady_steps;
  }
  out.detected = out.steady_steps >= 20 && off_mode >= 3 && out.multiple_fraction >= 0.0025;
  return out;
}

StreamTiming AnalyzeStreamTiming(const std::vector<double>& stamps_s,
                                 const std::vector<double>& values_row_major,
                                 const std::string& stream, const std::string& source) {
  StreamTiming timing;
  timing.stream = stream;
  timing.source = source;
  timing.records = static_cast<int>(stamps_s.size());
  const size_t n = stamps_s.size();
  const size_t width = n > 0 && values_row_major.size() % n == 0 ? values_row_major.size() / n : 0;
  // Keep the first of each run of exact duplicates.
  std::vector<double> t, values;
  std::vector<size_t> kept;
  for (size_t k = 0; k < n; ++k) {
    if (!kept.empty() && stamps_s[k] == stamps_s[kept.back()] &&
        (width == 0 || SameValues(values_row_major, width, k, kept.back()))) {
      ++timing.duplicates_dropped;
      continue;
    }
    kept.push_back(k);
    t.push_back(stamps_s[k]);
    values.insert(values.end(), values_row_major.begin() + k * width,
                  values_row_major.begin() + (k + 1) * width);
  }
  timing.samples = static_cast<int>(kept.size());
  AnalyzeGrid(t, &timing);
  if (width > 0 && kept.size() > 2) {
    std::vector<double> steps(kept.size() - 1);
    for (size_t k = 0; k + 1 < kept.size(); ++k) steps[k] = StepLength(values, width, k, k + 1);
    timing.repeated_values = CountHeldRepeats(steps);
    timing.values_quantized = Quantized(values, width, kept.size());
    if (!timing.values_quantized) {
      AddStepMultiples(AnalyzeDisplacementSteps(t, steps), &timing);
      return timing;
    }
  }
  timing_internal::Conclude(&timing);
  return timing;
}

void AddStepMultiples(const StepMultiples& steps, StreamTiming* timing) {
  timing->steady_steps = steps.steady_steps;
  timing->step_multiple_fraction = steps.multiple_fraction;
  timing->step_multiples_detected = steps.detected;
  timing_internal::Conclude(timing);
}

}  // namespace calib
