#include <calib/core/laser/laser_plausibility.h>
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

struct Finding {
  std::vector<std::string> why;  // Per interval: "" when plausible.
  int count = 0;
};

// The absurd values, and the kinds of implausibility a handful of intervals show (`allowed`).
Finding Judge(const std::vector<LaserInterval>& intervals) {
  const size_t n = intervals.size();
  const size_t allowed = std::max<size_t>(2, n / 50);
  Finding finding;
  finding.why.assign(n, "");
  std::vector<std::array<double, kNumQuantities>> values(n);
  for (size_t k = 0; k < n; ++k) {
    finding.why[k] = AbsurdField(intervals[k]);
    values[k] = Quantities(intervals[k]);
  }
  // Each rule applies only when few intervals break it.
  const auto apply = [&](const std::vector<size_t>& broken, const std::vector<std::string>& why) {
    if (broken.empty() || broken.size() > allowed) return;
    for (size_t i = 0; i < broken.size(); ++i) {
      if (finding.why[broken[i]].empty()) finding.why[broken[i]] = why[i];
    }
  };
  std::vector<size_t> broken;
  std::vector<std::string> why;
  for (size_t k = 0; k < n; ++k) {
    const double theta = intervals[k].sensor_motion(2);
    if (finding.why[k].empty() && std::abs(theta) > kTwoPi) {
      broken.push_back(k);
      why.push_back(Format("sm_theta = %.4g rad, more than a full turn in one interval", theta));
    }
  }
  apply(broken, why);
  if (n <= allowed) return finding;
  for (int q = 0; q < kNumQuantities; ++q) {
    std::vector<double> column;
    for (size_t k = 0; k < n; ++k) {
      if (finding.why[k].empty()) column.push_back(values[k][q]);
    }
    if (column.size() <= allowed) continue;
    std::nth_element(column.begin(), column.end() - 1 - allowed, column.end());
    const double scale = *(column.end() - 1 - allowed);
    if (!(scale > 0.0)) continue;
    broken.clear();
    why.clear();
    for (size_t k = 0; k < n; ++k) {
      if (finding.why[k].empty() && values[k][q] > kScaleFactor * scale) {
        broken.push_back(k);
        why.push_back(Format("%s = %.4g %s, %.3g times the log's typical value", kQuantityNames[q],
                             values[k][q], kQuantityUnits[q], values[k][q] / scale));
      }
    }
    apply(broken, why);
  }
  for (const std::string& w : finding.why) finding.count += w.empty() ? 0 : 1;
  return finding;
}

}  // namespace

void DropImplausibleIntervals(LaserLog* log) {
  const Finding finding = Judge(log->intervals);
  if (finding.count == 0) return;
  std::vector<LaserInterval> kept;
  kept.reserve(log->intervals.size());
  std::string first;
  bool gap = false;
  for (size_t k = 0; k < log->intervals.size(); ++k) {
    LaserInterval& interval = log->intervals[k];
    if (!finding.why[k].empty()) {
      if (first.empty()) {
        first = (interval.record > 0 ? "record " + std::to_string(interval.record)
                                     : "interval " + std::to_string(k + 1)) +
                (interval.line > 0 ? " (line " + std::to_string(interval.line) + ")" : "") + ": " +
                finding.why[k];
      }
      gap = true;
      continue;
    }
    interval.gap_before = interval.gap_before || (gap && !kept.empty());
    gap = false;
    kept.push_back(std::move(interval));
  }
  log->intervals = std::move(kept);
  log->warnings.push_back(log->source + ": " + std::to_string(finding.count) +
                          " implausible record(s) dropped (first: " + first + ")");
}

}  // namespace calib
