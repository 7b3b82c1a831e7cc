#include <calib/solvers/timing/pick_up_clock.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace calib {
namespace {

constexpr int kMinHolds = 10;
constexpr double kMaxViolationShare = 0.01;
constexpr double kSearchSpan = 0.5;  // P within (1 ± this)·median step.
constexpr int kCoarseSteps = 2000, kFineSteps = 80, kFineHalfWidth = 4;  // Grid steps.

// Consecutive records (distinct samples and held repeats, in stamp order): the earlier stamp,
// the later one, and whether the later one is a new sample.
struct Pair {
  double from_s, to_s;
  bool new_sample;
};

std::vector<Pair> Pairs(const StreamSamples& data) {
  std::vector<std::pair<double, bool>> records;
  for (const StreamSample& s : data.samples) records.push_back({s.stamp_s, true});
  for (const double stamp : data.held_stamp_s) records.push_back({stamp, false});
  std::stable_sort(records.begin(), records.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Pair> pairs;
  for (size_t k = 1; k < records.size(); ++k) {
    pairs.push_back({records[k - 1].first, records[k].first, records[k].second});
  }
  return pairs;
}

// The fewest constraints of `pairs` any phase breaks at period P, and that phase. With
// φ = (to − c) mod P, a new sample needs a tick of the sensor in (from, to]: φ < to − from; a held
// repeat needs none: φ ≥ to − from. Each broken set is an arc of c; a sweep finds the least covered
// point.
std::pair<int, double> BestPhase(const std::vector<Pair>& pairs, size_t count, double period) {
  std::vector<std::pair<double, int>> events;
  int always = 0;
  for (size_t i = 0; i < count; ++i) {
    const double gap = pairs[i].to_s - pairs[i].from_s;
    if (gap >= period) {
      always += !pairs[i].new_sample;
      continue;
    }
    // Broken for φ in [lo, hi): c in (to − hi, to − lo] (mod P).
    const double lo = pairs[i].new_sample ? gap : 0.0;
    const double hi = pairs[i].new_sample ? period : gap;
    const double start = std::fmod(std::fmod(pairs[i].to_s - hi, period) + period, period);
    const double end = start + (hi - lo);
    events.push_back({start, 1});
    if (end <= period) {
      events.push_back({end, -1});
    } else {
      events.push_back({period, -1});
      events.push_back({0.0, 1});
      events.push_back({end - period, -1});
    }
  }
  if (events.empty()) return {always, 0.0};
  std::sort(events.begin(), events.end());
  int covered = 0, best = static_cast<int>(count) + 1;
  double phase = 0.0;
  for (size_t i = 0; i + 1 < events.size(); ++i) {
    covered += events[i].second;
    if (events[i + 1].first > events[i].first && covered < best) {
      best = covered;
      phase = 0.5 * (events[i].first + events[i + 1].first);
    }
  }
  return {best + always, phase};
}

}  // namespace

std::optional<PickUpClock> FitPickUpClock(const StreamSamples& data) {
  if (static_cast<int>(data.held_stamp_s.size()) < kMinHolds || data.samples.size() < 2 ||
      !(data.sensor_period_s > 0.0)) {
    return std::nullopt;
  }
  const std::vector<Pair> pairs = Pairs(data);
  double lo = (1.0 - kSearchSpan) * data.sensor_period_s;
  double hi = (1.0 + kSearchSpan) * data.sensor_period_s;
  int steps = kCoarseSteps;
  double best_period = 0.0;
  // The basin of the true P narrows as 1/(samples used): grow the prefix as the grid refines.
  for (size_t count = 100;; count *= 4) {
    count = std::min(count, pairs.size());
    int best = static_cast<int>(count) + 1;
    for (int i = 0; i <= steps; ++i) {
      const double period = lo + (hi - lo) * i / steps;
      const int broken = BestPhase(pairs, count, period).first;
      if (broken < best) best = broken, best_period = period;
    }
    const double step = (hi - lo) / steps;
    lo = best_period - kFineHalfWidth * step;
    hi = best_period + kFineHalfWidth * step;
    steps = kFineSteps;
    if (count == pairs.size() && step < 1e-7 * best_period) break;
  }
  PickUpClock clock;
  clock.period_s = best_period;
  std::tie(clock.violations, clock.phase_s) = BestPhase(pairs, pairs.size(), best_period);
  clock.constraints = static_cast<int>(pairs.size());
  if (clock.violations > kMaxViolationShare * clock.constraints) return std::nullopt;
  const double first = std::floor((data.samples.front().stamp_s - clock.phase_s) / best_period);
  for (const StreamSample& s : data.samples) {
    clock.indices.push_back(std::floor((s.stamp_s - clock.phase_s) / best_period) - first);
  }
  return clock;
}

}  // namespace calib
