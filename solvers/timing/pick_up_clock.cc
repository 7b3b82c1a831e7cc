#include <calib/solvers/timing/pick_up_clock.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace calib {
namespace {

// Holds, or periods the motion counted other than the stamps' step, needed to tell P from the
// logger's own period.
constexpr int kMinHolds = 3;
constexpr double kMaxViolationShare = 0.01;
constexpr double kSearchSpan = 0.5;  // P within (1 ± this)·median step.
constexpr int kCoarseSteps = 10000;  // Over the span, on the first kFirstPairs pairs.
constexpr size_t kFirstPairs = 50;
constexpr size_t kMaxRuns = 400;      // Candidate basins refined.
constexpr int kPointsPerWindow = 16;  // Periods tried in a candidate's window per round.
// At most this many (period, pair) tests per window: a window that does not narrow with the prefix
// holds no basin of a pick-up clock (and would take ever more periods at the halving spacing).
constexpr double kMaxTestsPerWindow = 5e7;
constexpr int kMaxRounds = 40;

// Consecutive records (distinct samples and held repeats, in stamp order): the earlier stamp,
// the later one, and the sensor's ticks between them: 0 for a held repeat, the motion's count for
// a new sample where it has one, else −1 (at least one).
struct Pair {
  double from_s, to_s;
  int ticks;
};

std::vector<Pair> Pairs(const StreamSamples& data, const std::vector<int>& motion_periods) {
  struct Record {
    double stamp_s;
    int ticks;
  };
  std::vector<Record> records;
  for (size_t k = 0; k < data.samples.size(); ++k) {
    const int counted = k < motion_periods.size() ? motion_periods[k] : 0;
    records.push_back({data.samples[k].stamp_s, counted > 0 ? counted : -1});
  }
  for (const double stamp : data.held_stamp_s) records.push_back({stamp, 0});
  std::stable_sort(records.begin(), records.end(),
                   [](const Record& a, const Record& b) { return a.stamp_s < b.stamp_s; });
  std::vector<Pair> pairs;
  for (size_t k = 1; k < records.size(); ++k) {
    pairs.push_back({records[k - 1].stamp_s, records[k].stamp_s, records[k].ticks});
  }
  return pairs;
}

// The phases φ = (to − c) mod P that a pair allows, [lo, hi) within [0, P): the sensor ticks at
// to − φ − jP, so m ticks in (from, to] need gap − mP ≤ φ < gap − (m − 1)P. A new sample needs at
// least one: φ < gap; a held repeat none: φ ≥ gap.
void AllowedPhases(const Pair& pair, double period, double* lo, double* hi) {
  const double gap = pair.to_s - pair.from_s;
  if (pair.ticks < 0) {
    *lo = 0.0, *hi = std::min(gap, period);
  } else {
    *lo = std::max(0.0, gap - pair.ticks * period);
    *hi = std::min(period, gap - (pair.ticks - 1) * period);
  }
}

// Sorts the events (phase, ±1) by phase in [0, period], ties −1 first, in O(n): a bucket per
// event, then insertion sort inside each bucket (a sort where they pile up). BestPhase is called
// tens of thousands of times per log, on up to 10⁴ pairs; a comparison sort took most of the
// pick-up search.
void SortEvents(double period, std::vector<std::pair<double, int>>* events,
                std::vector<std::pair<double, int>>* sorted, std::vector<int>* bucket_end) {
  const int buckets = static_cast<int>(events->size());
  const double scale = buckets / period;
  const auto bucket = [&](double phase) {
    return std::clamp(static_cast<int>(phase * scale), 0, buckets - 1);
  };
  bucket_end->assign(buckets + 1, 0);
  for (const auto& e : *events) ++(*bucket_end)[bucket(e.first) + 1];
  for (int b = 0; b < buckets; ++b) (*bucket_end)[b + 1] += (*bucket_end)[b];
  sorted->resize(events->size());
  for (const auto& e : *events) (*sorted)[(*bucket_end)[bucket(e.first)]++] = e;
  // bucket_end[b] is now the end of bucket b.
  int begin = 0;
  for (int b = 0; b < buckets; ++b) {
    const int end = (*bucket_end)[b];
    if (end - begin > 32) {  // Phases that pile up (stamps on a grid of P) sort as usual.
      std::sort(sorted->begin() + begin, sorted->begin() + end);
      begin = end;
      continue;
    }
    for (int i = begin + 1; i < end; ++i) {
      const std::pair<double, int> e = (*sorted)[i];
      int j = i;
      for (; j > begin && e < (*sorted)[j - 1]; --j) (*sorted)[j] = (*sorted)[j - 1];
      (*sorted)[j] = e;
    }
    begin = end;
  }
}

// The fewest constraints of `pairs` any phase breaks at period P, and that phase. Each pair breaks
// for φ outside its allowed range, an arc or two of c; a sweep finds the least covered point.
std::pair<int, double> BestPhase(const std::vector<Pair>& pairs, size_t count, double period) {
  thread_local std::vector<std::pair<double, int>> events, sorted;
  thread_local std::vector<int> bucket_end;
  events.clear();
  const double inverse_period = 1.0 / period;
  int wrapped = 0;  // Arcs across P ≡ 0: they cover the sweep's start.
  // Broken for φ in [a, b): c in (to − b, to − a] (mod P).
  const auto broken = [&](double to, double a, double b) {
    if (!(b > a)) return;
    const double x = to - b;
    const double start = std::clamp(x - period * std::floor(x * inverse_period), 0.0, period);
    const double end = start + (b - a);
    if (end <= period) {
      events.push_back({start, 1});
      events.push_back({end, -1});
    } else {
      ++wrapped;
      events.push_back({end - period, -1});
      events.push_back({start, 1});
    }
  };
  int always = 0;
  for (size_t i = 0; i < count; ++i) {
    double lo = 0.0, hi = 0.0;
    AllowedPhases(pairs[i], period, &lo, &hi);
    if (!(hi > lo)) {
      ++always;
      continue;
    }
    broken(pairs[i].to_s, 0.0, lo);
    broken(pairs[i].to_s, hi, period);
  }
  if (events.empty()) return {always + wrapped, 0.0};
  SortEvents(period, &events, &sorted, &bucket_end);
  // The stretches before the first event and after the last are covered by the wrapped arcs only.
  int covered = wrapped, best = wrapped;
  double phase = 0.5 * sorted.front().first;
  if (!(sorted.front().first > 0.0)) best = static_cast<int>(count) + 1;
  if (sorted.back().first < period && wrapped < best) {
    best = wrapped;
    phase = 0.5 * (sorted.back().first + period);
  }
  for (size_t i = 0; i + 1 < sorted.size(); ++i) {
    covered += sorted[i].second;
    if (sorted[i + 1].first > sorted[i].first && covered < best) {
      best = covered;
      phase = 0.5 * (sorted[i].first + sorted[i + 1].first);
    }
  }
  return {best + always, phase};
}

// A period's search window, the fewest constraints broken in it and the periods that break them.
struct Candidate {
  double lo_s, hi_s, period_s;
  int broken;
  double first_s = 0.0, last_s = 0.0;
};

// Each window searched on `count` pairs at kPointsPerWindow + 1 periods or more, at most
// `spacing` apart, then shrunk to the periods that break the fewest and one spacing either side;
// the windows within one of the fewest kept (those that would need more than kMaxTestsPerWindow
// dropped).
std::vector<Candidate> Narrow(const std::vector<Pair>& pairs, size_t count, double max_spacing,
                              std::vector<Candidate> candidates) {
  int fewest = static_cast<int>(count) + 1;
  for (Candidate& c : candidates) {
    c.broken = static_cast<int>(count) + 1;
    const double needed = std::ceil((c.hi_s - c.lo_s) / max_spacing);
    if (needed * static_cast<double>(count) > kMaxTestsPerWindow) continue;
    const int n = !(c.hi_s > c.lo_s) ? 0 : std::max(kPointsPerWindow, static_cast<int>(needed));
    const double spacing = n > 0 ? (c.hi_s - c.lo_s) / n : 0.0;
    for (int i = 0; i <= n; ++i) {
      const double period = c.lo_s + spacing * i;
      const int broken = BestPhase(pairs, count, period).first;
      if (broken < c.broken) c.broken = broken, c.first_s = period;
      if (broken == c.broken) c.last_s = period;
    }
    c.period_s = 0.5 * (c.first_s + c.last_s);
    c.lo_s = c.first_s - spacing;
    c.hi_s = c.last_s + spacing;
    fewest = std::min(fewest, c.broken);
  }
  std::vector<Candidate> kept;
  for (const Candidate& c : candidates) {
    if (c.broken <= fewest + 1 && c.broken <= static_cast<int>(count)) kept.push_back(c);
  }
  return kept;
}

}  // namespace

std::optional<PickUpClock> FitPickUpClock(const StreamSamples& data,
                                          const std::vector<int>& motion_periods, double period_s) {
  const double guess_s = period_s > 0.0 ? period_s : data.sensor_period_s;
  if (data.samples.size() < 2 || !(guess_s > 0.0)) return std::nullopt;
  int telling = static_cast<int>(data.held_stamp_s.size());
  for (size_t k = 1; k < data.samples.size() && k < motion_periods.size(); ++k) {
    const double steps =
        std::round((data.samples[k].stamp_s - data.samples[k - 1].stamp_s) / guess_s);
    telling += motion_periods[k] > 0 && motion_periods[k] != steps;
  }
  if (telling < kMinHolds) return std::nullopt;
  const std::vector<Pair> pairs = Pairs(data, motion_periods);
  // The first pairs hold few held repeats, so fractions and neighbours of P break as few of them
  // as P does: every run of the coarse grid within one of the fewest is a candidate. Longer
  // prefixes narrow the basin of the true P as 1/(pairs used), and the candidates with it.
  size_t count = std::min<size_t>(kFirstPairs, pairs.size());
  const double step = 2.0 * kSearchSpan * guess_s / kCoarseSteps;
  const double lo = (1.0 - kSearchSpan) * guess_s;
  std::vector<Candidate> candidates;
  for (int i = 0; i <= kCoarseSteps; ++i) {
    candidates.push_back({lo + step * i, lo + step * i, lo + step * i, 0});
  }
  candidates = Narrow(pairs, count, step, std::move(candidates));
  std::vector<Candidate> runs;  // Neighbouring grid points merged, one step of margin.
  for (const Candidate& c : candidates) {
    if (!runs.empty() && c.period_s - runs.back().hi_s < 1.5 * step) {
      runs.back().hi_s = c.period_s + step;
    } else {
      runs.push_back({c.period_s - step, c.period_s + step, c.period_s, c.broken});
    }
  }
  if (runs.size() > kMaxRuns) return std::nullopt;
  candidates = std::move(runs);
  // On all pairs, until no window shrinks by half: the least-broken range is then resolved.
  const auto width = [&] {
    double total = 0.0;
    for (const Candidate& c : candidates) total += c.hi_s - c.lo_s;
    return total;
  };
  // The basin narrows as 1/(pairs used): twice the pairs each round, half the spacing.
  double spacing = 0.5 * step;
  for (int round = 0; round < kMaxRounds; ++round, spacing *= 0.5) {
    const bool all = count == pairs.size();
    const double before = width();
    count = std::min(2 * count, pairs.size());
    candidates = Narrow(pairs, count, spacing, std::move(candidates));
    if (all && width() > 0.5 * before) break;
  }
  if (candidates.empty()) return std::nullopt;
  const Candidate best =
      *std::min_element(candidates.begin(), candidates.end(),
                        [](const Candidate& a, const Candidate& b) { return a.broken < b.broken; });
  const double best_period = best.period_s;
  PickUpClock clock;
  clock.period_s = best_period;
  clock.period_stddev_s = (best.hi_s - best.lo_s) / std::sqrt(12.0);
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
