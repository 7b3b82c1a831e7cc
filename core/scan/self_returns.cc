#include <calib/core/scan/self_returns.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace calib {
namespace {

bool SameBeams(const LaserScan& a, const LaserScan& b) {
  return a.ranges_m.size() == b.ranges_m.size() &&
         std::abs(a.angle_min_rad - b.angle_min_rad) < 1e-9 &&
         std::abs(a.angle_increment_rad - b.angle_increment_rad) < 1e-12;
}

struct BeamStats {
  int returns = 0;
  double median_m = 0.0, steady_share = 0.0;
};

BeamStats Stats(const std::vector<const LaserScan*>& scans, int beam,
                const SelfReturnOptions& o, std::vector<float>* ranges) {
  ranges->clear();
  for (const LaserScan* s : scans) {
    if (s->IsReturn(beam)) ranges->push_back(s->ranges_m[beam]);
  }
  BeamStats out;
  out.returns = static_cast<int>(ranges->size());
  if (ranges->empty()) return out;
  std::nth_element(ranges->begin(), ranges->begin() + ranges->size() / 2, ranges->end());
  out.median_m = (*ranges)[ranges->size() / 2];
  const double tolerance = std::max(o.tolerance_m, 0.02 * out.median_m);
  const auto steady = std::count_if(ranges->begin(), ranges->end(), [&](float r) {
    return std::abs(r - out.median_m) <= tolerance;
  });
  out.steady_share = static_cast<double>(steady) / ranges->size();
  return out;
}

}  // namespace

SelfReturns FindSelfReturns(const std::vector<LaserScan>& scans, const SelfReturnOptions& o) {
  SelfReturns out;
  if (scans.size() < 10) return out;
  for (const LaserScan& s : scans) {
    if (!SameBeams(s, scans.front())) return out;
  }
  std::vector<const LaserScan*> sample;
  const size_t step = std::max<size_t>(1, scans.size() / o.max_scans);
  for (size_t i = 0; i < scans.size(); i += step) sample.push_back(&scans[i]);
  const int n = static_cast<int>(scans.front().ranges_m.size());
  std::vector<float> ranges;
  std::vector<char> body(n, 0);
  int scene = 0, steady_scene = 0;
  for (int i = 0; i < n; ++i) {
    const BeamStats b = Stats(sample, i, o, &ranges);
    if (b.returns < o.return_share * sample.size()) continue;
    const bool steady = b.steady_share >= o.steady_share;
    if (b.median_m > o.max_range_m) {
      ++scene;
      steady_scene += steady;
    } else if (steady) {
      body[i] = 1;
    }
  }
  if (scene < 20 || steady_scene > o.max_steady_scene_share * scene) return out;
  double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
  for (int i = 0; i < n; ++i) {
    const bool near = body[i] || (i > 0 && body[i - 1]) || (i + 1 < n && body[i + 1]);
    if (!near) continue;
    out.beams.push_back(i);
    if (body[i]) {
      const BeamStats b = Stats(sample, i, o, &ranges);
      lo = std::min(lo, b.median_m);
      hi = std::max(hi, b.median_m);
    }
  }
  if (out.beams.empty()) return out;
  out.min_range_m = lo;
  out.max_range_m = hi;
  const LaserScan& s = scans.front();
  for (size_t k = 0; k < out.beams.size(); ++k) {
    if (k == 0 || out.beams[k] != out.beams[k - 1] + 1) {
      out.sectors_rad.emplace_back(s.BeamAngle(out.beams[k]), s.BeamAngle(out.beams[k]));
    }
    out.sectors_rad.back().second = s.BeamAngle(out.beams[k]);
  }
  return out;
}

std::string SelfReturns::Describe(int scans) const {
  std::string sectors;
  char text[96];
  for (const auto& [from, to] : sectors_rad) {
    std::snprintf(text, sizeof(text), "%s%.0f° to %.0f°", sectors.empty() ? "" : ", ",
                  from * 180.0 / M_PI, to * 180.0 / M_PI);
    sectors += text;
  }
  std::snprintf(text, sizeof(text), ") return from %.2f–%.2f m in scan after scan of %d",
                min_range_m, max_range_m, scans);
  return std::to_string(beams.size()) + " beams (" + sectors + text +
         ", whatever the robot does: the robot's own body, left out of the matching";
}

void MaskBeams(const std::vector<int>& beams, std::vector<LaserScan>* scans) {
  for (LaserScan& s : *scans) {
    for (const int i : beams) {
      if (i >= 0 && i < static_cast<int>(s.ranges_m.size())) {
        s.ranges_m[i] = std::numeric_limits<float>::quiet_NaN();
      }
    }
  }
}

}  // namespace calib
