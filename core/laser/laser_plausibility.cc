#include <calib/core/huge_pages.h>
#include <calib/core/laser/laser_plausibility.h>
#include <calib/core/order_statistic.h>
#include <calib/core/text_format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

namespace calib {
namespace {

constexpr double kAbsurdValue = 1e9;
constexpr double kTwoPi = 6.283185307179586;
constexpr double kScaleFactor = 1000.0;

// The quantities bounded relative to the log: T, |Δφ_l|, |Δφ_r|, |sm_xy|.
enum Quantity { kDuration, kLeftRotation, kRightRotation, kDisplacement, kNumQuantities };
constexpr const char* kQuantityNames[kNumQuantities] = {"T", "the left wheel's rotation φ_l·T",
                                                        "the right wheel's rotation φ_r·T",
                                                        "the displacement |sm_xy|"};
constexpr const char* kQuantityUnits[kNumQuantities] = {"s", "rad", "rad", "m"};

std::array<double, kNumQuantities> Quantities(const LaserInterval& interval) {
  double left = interval.left_speed * interval.duration_s;
  double right = interval.right_speed * interval.duration_s;
  if (!interval.steps.empty()) {
    left = right = 0.0;
    for (const WheelStep& step : interval.steps) left += step.left_rad, right += step.right_rad;
  }
  return {interval.duration_s, std::abs(left), std::abs(right),
          interval.sensor_motion.head<2>().norm()};
}

bool Absurd(const LaserInterval& i) {
  return !(std::abs(i.duration_s) <= kAbsurdValue && std::abs(i.left_speed) <= kAbsurdValue &&
           std::abs(i.right_speed) <= kAbsurdValue &&
           i.sensor_motion.cwiseAbs().maxCoeff() <= kAbsurdValue);
}

std::string AbsurdField(const LaserInterval& i) {
  const std::pair<const char*, double> fields[] = {
      {"T", i.duration_s},          {"phi_l", i.left_speed},      {"phi_r", i.right_speed},
      {"sm_x", i.sensor_motion(0)}, {"sm_y", i.sensor_motion(1)}, {"sm_theta", i.sensor_motion(2)}};
  for (const auto& [name, value] : fields) {
    if (!(std::abs(value) <= kAbsurdValue))
      return Format("%s = %.3g, which no unit explains", name, value);
  }
  return "";
}

// The implausible intervals and why the first of them is. Reasons are formatted only for the
// intervals a rule breaks (at most `allowed` per rule): a long log's check is a few passes.
struct Finding {
  std::vector<bool> implausible;  // Per interval.
  size_t count = 0;
  size_t first = 0;       // The first implausible interval (when count > 0).
  std::string first_why;  // Its reason: the first rule it broke.
};

class Judge {
 public:
  // One pass over the intervals (a long log's are far larger than the cache); the rules then read
  // the quantities.
  explicit Judge(const std::vector<LaserInterval>& intervals)
      : intervals_(intervals), allowed_(std::max<size_t>(2, intervals.size() / 50)) {
    finding_.implausible.assign(intervals.size(), false);
    for (std::vector<double>& column : values_) ReserveOnHugePages(&column, intervals.size());
    turns_.resize(intervals.size());
    for (size_t k = 0; k < intervals.size(); ++k) {
      const std::array<double, kNumQuantities> values = Quantities(intervals[k]);
      for (int q = 0; q < kNumQuantities; ++q) values_[q].push_back(values[q]);
      turns_[k] = std::abs(intervals[k].sensor_motion(2)) > kTwoPi;
      if (Absurd(intervals[k])) Mark(k, AbsurdField(intervals[k]));
    }
  }

  // The absurd values, and the kinds of implausibility a handful of intervals show (`allowed`).
  Finding Run() && {
    const size_t n = intervals_.size();
    Apply([&](size_t k) { return turns_[k]; },
          [&](size_t k) {
            return Format("sm_theta = %.4g rad, more than a full turn in one interval",
                          intervals_[k].sensor_motion(2));
          });
    if (n <= allowed_) return std::move(finding_);
    std::vector<double> column;  // One buffer for every quantity: its pages fault in once.
    ReserveOnHugePages(&column, n);
    for (int q = 0; q < kNumQuantities; ++q) {
      const std::vector<double>& values = values_[q];
      column.clear();
      if (finding_.count == 0) {
        column.assign(values.begin(), values.end());
      } else {
        for (size_t k = 0; k < n; ++k) {
          if (!finding_.implausible[k]) column.push_back(values[k]);
        }
      }
      if (column.size() <= allowed_) continue;
      const double scale = KthSmallest(&column, column.size() - 1 - allowed_);
      if (!(scale > 0.0)) continue;
      Apply([&](size_t k) { return values[k] > kScaleFactor * scale; },
            [&](size_t k) {
              const double value = values[k];
              return Format("%s = %.4g %s, %.3g times the log's typical value", kQuantityNames[q],
                            value, kQuantityUnits[q], value / scale);
            });
    }
    return std::move(finding_);
  }

 private:
  void Mark(size_t k, const std::string& why) {
    if (finding_.count == 0 || k < finding_.first) {
      finding_.first = k;
      finding_.first_why = why;
    }
    finding_.implausible[k] = true;
    ++finding_.count;
  }

  // A rule applies only when few intervals (not yet implausible) break it.
  template <typename Breaks, typename Why>
  void Apply(const Breaks& breaks, const Why& why) {
    std::vector<size_t> broken;
    for (size_t k = 0; k < intervals_.size() && broken.size() <= allowed_; ++k) {
      if (!finding_.implausible[k] && breaks(k)) broken.push_back(k);
    }
    if (broken.size() > allowed_) return;
    for (const size_t k : broken) Mark(k, why(k));
  }

  const std::vector<LaserInterval>& intervals_;
  const size_t allowed_;
  std::array<std::vector<double>, kNumQuantities> values_;  // By quantity: each pass reads one.
  std::vector<bool> turns_;                                 // More than a full turn.
  Finding finding_;
};

}  // namespace

void DropImplausibleIntervals(LaserLog* log) {
  const Finding finding = Judge(log->intervals).Run();
  if (finding.count == 0) return;
  std::vector<LaserInterval>& intervals = log->intervals;
  const LaserInterval& first = intervals[finding.first];
  const std::string name = (first.record > 0 ? "record " + std::to_string(first.record)
                                             : "interval " + std::to_string(finding.first + 1)) +
                           (first.line > 0 ? " (line " + std::to_string(first.line) + ")" : "");
  // In place: a long log is not copied.
  size_t kept = 0;
  bool gap = false;
  for (size_t k = 0; k < intervals.size(); ++k) {
    if (finding.implausible[k]) {
      gap = true;
      continue;
    }
    intervals[k].gap_before = intervals[k].gap_before || (gap && kept > 0);
    gap = false;
    if (kept != k) intervals[kept] = std::move(intervals[k]);
    ++kept;
  }
  intervals.erase(intervals.begin() + static_cast<std::ptrdiff_t>(kept), intervals.end());
  log->warnings.push_back(log->source + ": " + std::to_string(finding.count) +
                          " implausible record(s) dropped (first: " + name + ": " +
                          finding.first_why + ")");
}

}  // namespace calib
