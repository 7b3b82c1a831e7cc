// The verdict and notes of a stream timing, pooling over runs, and the readers' duplicates.
#include <calib/core/text_format.h>
#include <calib/core/text_number.h>
#include <calib/core/timing/sample_clock.h>
#include <calib/core/timing/stamp_timing.h>
#include <calib/core/timing/stamp_timing_internal.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace calib {
namespace timing_internal {
namespace {

constexpr double kRegularFraction = 0.02;       // Jitter ≤ 2 % of the period: a regular grid.
constexpr double kPickupFraction = 0.05;        // Jitter > 5 % of the period ...
constexpr double kPickupCorrelation = -0.2;     // ... with anti-correlated intervals: pick-up.
constexpr double kFreeRunningMultiples = 0.25;  // Intervals at k ≥ 2 periods: another clock.

std::string Format(const char* format, double a, double b = 0.0, double c = 0.0) {
  char text[400];
  std::snprintf(text, sizeof(text), format, a, b, c);
  return text;
}

}  // namespace

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const size_t half = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + half, values.end());
  const double upper = values[half];
  if (values.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(values.begin(), values.begin() + half));
}

bool SteadyWindow(const double* d, int w, double tolerance, std::vector<int>* k_of) {
  std::vector<double> moving;
  for (int i = 0; i < w; ++i) {
    if (d[i] > 0.0) moving.push_back(d[i]);
  }
  if (2 * static_cast<int>(moving.size()) < w) return false;
  const double typical = Median(moving);
  for (int n = 1; n <= 3; ++n) {
    const double unit = typical / n;
    k_of->assign(w, 0);
    bool fits = true;
    for (int i = 0; i < w && fits; ++i) {
      const double ratio = d[i] / unit;
      const double k = std::round(ratio);
      fits = k <= 4 && std::abs(ratio - k) <= tolerance;
      // Converted only when it fits: a step of 1e13 units is no int.
      (*k_of)[i] = fits ? static_cast<int>(k) : 0;
    }
    for (int i = 0; i < w && fits; ++i) {
      // A zero inside motion, caught up by the next step; not a start or a stop.
      if ((*k_of)[i] == 0) fits = i > 0 && i + 1 < w && (*k_of)[i - 1] > 0 && (*k_of)[i + 1] >= 2;
    }
    if (fits) return true;
  }
  return false;
}

// Irregular but exact stamps (independent intervals, as the simulator's 0.8 s ± 0.02 s) are not
// `regular` (the intervals' random walk shows as scatter about the local grid) but are taken as
// sample times: their intervals are uncorrelated, where scatter added to a grid gives −0.5.
void Conclude(StreamTiming* t) {
  const double period = t->period_s;
  const bool known = t->samples >= 3 && period > 0.0;
  t->regular = known && t->jitter_s <= kRegularFraction * period;
  const bool clustered =
      known && t->intervals >= 8 && t->multiple_fraction >= kFreeRunningMultiples;
  const bool held = t->repeated_values >= 2;
  t->free_running_signature = clustered || held || t->step_multiples_detected;
  const bool pickup = known && t->jitter_s > kPickupFraction * period &&
                      t->interval_correlation < kPickupCorrelation;
  t->stamps_are_sample_times = !(t->free_running_signature || pickup);

  const std::string& s = t->source.empty() ? t->stream : t->source;
  std::vector<std::string>& notes = t->notes;
  notes.clear();
  if (!known) {
    notes.push_back(s + ": " + std::to_string(t->samples) +
                    " sample(s): too few stamps to judge their timing.");
    return;
  }
  notes.push_back(s + ": " + std::to_string(t->samples) + " samples" +
                  Format(", period %.4g ms, stamp jitter %.3g ms (%.2g %% of the period).",
                         period * 1e3, t->jitter_s * 1e3, 100.0 * t->jitter_s / period));
  if (t->duplicates_dropped > 0) {
    notes.push_back(s + ": " + std::to_string(t->duplicates_dropped) +
                    " exact duplicate record(s) (same stamp, same values) dropped.");
  }
  if (t->gaps > 0) {
    notes.push_back(s + ": " + std::to_string(t->gaps) +
                    Format(" gap(s) longer than 5 periods, the longest %.4g s.", t->longest_gap_s));
  }
  if (clustered) {
    notes.push_back(s + Format(": stamp intervals cluster at whole multiples of a %.4g ms base "
                               "period (%.3g %% at two or more): a free-running sensor picked up "
                               "by a logger on another clock.",
                               period * 1e3, 100.0 * t->multiple_fraction));
  } else if (t->multiple_fraction > 0.0) {
    notes.push_back(s + Format(": %.3g %% of the stamp intervals span two or more periods "
                               "(missed samples; counted apart from the jitter).",
                               100.0 * t->multiple_fraction));
  }
  if (held) {
    notes.push_back(s + ": " + std::to_string(t->repeated_values) +
                    " record(s) repeat the previous values with a later stamp inside motion: a "
                    "held sample picked up again.");
  }
  if (t->step_multiples_detected) {
    notes.push_back(s + Format(": at steady motion %.3g %% of the displacement steps are off "
                               "their usual whole number of unit steps (0, 1, 2, ...): the "
                               "logger picks up the latest sample of a free-running sensor.",
                               100.0 * t->step_multiple_fraction));
  }
  if (!t->stamps_are_sample_times) {
    notes.push_back(s + Format(": stamps scatter by %.3g ms about a %.4g ms grid; they are "
                               "pick-up times, not sample times.",
                               t->jitter_s * 1e3, period * 1e3));
  } else if (!t->regular) {
    notes.push_back(s + Format(": the intervals vary (stamps %.3g ms off a local grid) but "
                               "independently (lag-1 correlation %.2f), as an irregular "
                               "sampler's own times do; taken as sample times.",
                               t->jitter_s * 1e3, t->interval_correlation));
  }
}

}  // namespace timing_internal

StreamTiming PoolStreamTiming(const std::vector<StreamTiming>& runs, const std::string& stream,
                              const std::string& source) {
  StreamTiming pooled;
  pooled.stream = stream;
  pooled.source = source;
  double weight = 0.0, jitter2 = 0.0, scatter2 = 0.0, correlation = 0.0, intervals = 0.0;
  double multiples = 0.0, steps = 0.0;
  for (const StreamTiming& run : runs) {
    pooled.records += run.records;
    pooled.samples += run.samples;
    pooled.duplicates_dropped += run.duplicates_dropped;
    pooled.repeated_values += run.repeated_values;
    pooled.gaps += run.gaps;
    pooled.longest_gap_s = std::max(pooled.longest_gap_s, run.longest_gap_s);
    pooled.intervals += run.intervals;
    pooled.steady_steps += run.steady_steps;
    pooled.step_multiples_detected |= run.step_multiples_detected;
    pooled.values_quantized |= run.values_quantized;
    if (run.period_s > 0.0) {
      weight += run.samples;
      pooled.period_s += run.samples * run.period_s;
      jitter2 += run.samples * run.jitter_s * run.jitter_s;
    }
    intervals += run.intervals;
    correlation += run.intervals * run.interval_correlation;
    scatter2 += run.intervals * run.pickup_scatter_s * run.pickup_scatter_s;
    multiples += run.intervals * run.multiple_fraction;
    steps += run.steady_steps * run.step_multiple_fraction;
  }
  if (weight > 0.0) {
    pooled.period_s /= weight;
    pooled.jitter_s = std::sqrt(jitter2 / weight);
  }
  if (intervals > 0.0) {
    pooled.interval_correlation = correlation / intervals;
    pooled.pickup_scatter_s = std::sqrt(scatter2 / intervals);
    pooled.multiple_fraction = multiples / intervals;
  }
  if (pooled.steady_steps > 0) pooled.step_multiple_fraction = steps / pooled.steady_steps;
  timing_internal::Conclude(&pooled);
  bool all_sample_times = true;
  for (const StreamTiming& run : runs) all_sample_times &= run.stamps_are_sample_times;
  if (!all_sample_times && pooled.stamps_are_sample_times) {
    pooled.stamps_are_sample_times = false;
  }
  pooled.notes.insert(pooled.notes.begin() + std::min<size_t>(1, pooled.notes.size()),
                      (source.empty() ? stream : source) + ": figures pooled over " +
                          std::to_string(runs.size()) +
                          " run(s) (each run analysed on its own clock).");
  for (const StreamTiming& run : runs) {
    if (run.stamps_are_sample_times) continue;
    pooled.notes.insert(pooled.notes.end(), run.notes.begin() + 1, run.notes.end());
  }
  return pooled;
}

Status CheckStampUnit(const std::vector<double>& stamps_s, const std::string& source,
                      const std::string& field) {
  if (stamps_s.size() < 3) return Status::Ok();
  const double step = MedianStep(stamps_s);
  const double largest = std::max(std::abs(stamps_s.front()), std::abs(stamps_s.back()));
  if (!(step > kMaxStampStepS) && !(largest > 1e14)) return Status::Ok();
  const struct {
    double per_second;
    const char* name;
  } units[] = {{1e3, "milliseconds"}, {1e6, "microseconds"}, {1e9, "nanoseconds"}};
  std::string guess = "another unit";
  for (const auto& unit : units) {
    if (step / unit.per_second <= kMaxStampStepS && largest / unit.per_second <= 1e14) {
      guess = Format("%s (divide %s by %.0e)", unit.name, field.c_str(), unit.per_second);
      break;
    }
  }
  return Status::InvalidInput(
      source +
      Format(": the stamps step by %.6g (median) and reach %.6g; %s is read in seconds, ", step,
             largest, field.c_str()) +
      "and these look like " + guess);
}

Status DropExactDuplicates(const std::string& source, StreamRecords* records, int* dropped) {
  const size_t n = records->stamps_s.size();
  const size_t width = records->value_names.size();
  const auto where = [&](size_t k) {
    return records->lines.empty() ? "record " + std::to_string(k + 1)
                                  : "line " + std::to_string(records->lines[k]);
  };
  size_t kept = 0;  // records [0, kept) are the kept ones, in order.
  for (size_t k = 0; k < n; ++k) {
    if (kept > 0 && records->stamps_s[k] == records->stamps_s[kept - 1]) {
      const double* a = &records->values[(kept - 1) * width];
      const double* b = &records->values[k * width];
      const size_t differ = static_cast<size_t>(std::mismatch(a, a + width, b).first - a);
      if (differ == width) continue;  // An exact duplicate.
      return Status::InvalidInput(source + ": " + where(kept - 1) + " and " + where(k) +
                                  " share t=" + Num(records->stamps_s[k]) + " but differ in " +
                                  records->value_names[differ]);
    }
    records->stamps_s[kept] = records->stamps_s[k];
    std::copy(records->values.begin() + k * width, records->values.begin() + (k + 1) * width,
              records->values.begin() + kept * width);
    if (!records->lines.empty()) records->lines[kept] = records->lines[k];
    ++kept;
  }
  records->stamps_s.resize(kept);
  records->values.resize(kept * width);
  if (!records->lines.empty()) records->lines.resize(kept);
  if (dropped != nullptr) *dropped = static_cast<int>(n - kept);
  return Status::Ok();
}

}  // namespace calib
