#include <calib/core/scan/csm_log.h>
#include <calib/core/text_number.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace calib {
namespace {

std::string TimeVal(double t) {
  const double s = std::floor(t);
  char text[48];
  std::snprintf(text, sizeof(text), "[%.0f, %.0f]", s,
                std::min(999999.0, std::round(1e6 * (t - s))));
  return text;
}

}  // namespace

std::string CsmLogText(const std::vector<LaserScan>& scans,
                       const std::vector<EncoderSample>& encoders, double counts_per_turn,
                       double epoch_s) {
  std::string out;
  const double per_rad = counts_per_turn / (2.0 * M_PI);
  size_t e = 0;
  char number[32];
  for (const LaserScan& scan : scans) {
    while (e + 1 < encoders.size() && encoders[e + 1].t_s <= scan.stamp_s) ++e;
    const int n = static_cast<int>(scan.ranges_m.size());
    out += "{\"nrays\": " + std::to_string(n) + ", \"min_theta\": " + Num(scan.BeamAngle(0)) +
           ", \"max_theta\": " + Num(scan.BeamAngle(n - 1)) + ", \"theta\": [";
    for (int i = 0; i < n; ++i) out += (i ? ", " : "") + Num(scan.BeamAngle(i));
    out += "], \"readings\": [";
    for (int i = 0; i < n; ++i) {
      std::snprintf(number, sizeof(number), "%.6f", scan.ranges_m[i]);
      out += (i ? ", " : "") + std::string(scan.IsReturn(i) ? number : "null");
    }
    out += "], \"valid\": [";
    for (int i = 0; i < n; ++i) out += (i ? ", " : "") + std::string(scan.IsReturn(i) ? "1" : "0");
    out += "], \"timestamp\": " + TimeVal(epoch_s + scan.stamp_s);
    if (!encoders.empty()) {
      const EncoderSample& s = encoders[e];
      const std::string at = TimeVal(epoch_s + s.t_s);
      out += ", \"left\": " + Num(std::round(per_rad * s.left_rad)) +
             ", \"right\": " + Num(std::round(per_rad * s.right_rad)) +
             ", \"leftTimestamp\": " + at + ", \"rightTimestamp\": " + at;
    }
    out += "}\n";
  }
  return out;
}

}  // namespace calib
