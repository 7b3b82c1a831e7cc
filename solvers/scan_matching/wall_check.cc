#include <calib/core/order_statistic.h>
#include <calib/solvers/scan_matching/wall_check.h>

#include <algorithm>
#include <cmath>

namespace calib {
namespace {

constexpr double kQuarterTurn = 0.5 * M_PI;
constexpr int kStretches = 10;
constexpr size_t kUnwrapScans = 15;
// The chords a scan's walls are read from: about kChordM long, within [kMinChordM, kMaxChordM].
constexpr double kChordM = 0.3, kMinChordM = 0.05, kMaxChordM = 1.0;
// A scan sees walls when its chords agree on a direction over this much length (m).
constexpr double kMinWallsM = 1.0;
constexpr double kMaxScatterRad = 8.0 * M_PI / 180.0;

double Wrap90(double a) {
  return a - kQuarterTurn * std::floor((a + 0.5 * kQuarterTurn) / kQuarterTurn);
}

// The robot's heading at time t under `odometry`, up to a constant: r_r φ_r − r_l φ_l over b, the
// wheel angles linear between their samples.
class WheelHeading {
 public:
  explicit WheelHeading(const std::vector<EncoderSample>& wheels) : wheels_(wheels) {}
  double At(double t, const OdometryParams& o) {
    while (i_ + 2 < wheels_.size() && wheels_[i_ + 1].t_s <= t) ++i_;
    while (i_ > 0 && wheels_[i_].t_s > t) --i_;
    const EncoderSample &a = wheels_[i_], &b = wheels_[i_ + 1];
    const double w = b.t_s > a.t_s ? (t - a.t_s) / (b.t_s - a.t_s) : 0.0;
    const double left = a.left_rad + w * (b.left_rad - a.left_rad);
    const double right = a.right_rad + w * (b.right_rad - a.right_rad);
    return (o.right_radius_m * right - o.left_radius_m * left) / o.wheelbase_m;
  }

 private:
  const std::vector<EncoderSample>& wheels_;
  size_t i_ = 0;
};

struct Bearing {
  double t_s, wall_rad;  // The scan's time on the wheels' clock, the walls' direction in it.
};

WallHeading Trend(const std::vector<Bearing>& bearings, const std::vector<EncoderSample>& wheels,
                  const OdometryParams& odometry) {
  WheelHeading heading(wheels);
  // The walls' direction in the building, unwrapped against the median of the last scans' (one
  // scan's odd direction must not turn all after it by 90°).
  std::vector<double> t, v, recent;
  for (const Bearing& b : bearings) {
    const double direction = Wrap90(heading.At(b.t_s, odometry) + b.wall_rad);
    recent.assign(v.end() - std::min<size_t>(v.size(), kUnwrapScans), v.end());
    const double reference = recent.empty() ? direction : UpperMedian(&recent);
    t.push_back(b.t_s);
    v.push_back(reference + Wrap90(direction - reference));
  }
  const double t0 = t.front(), span = t.back() - t.front();
  std::vector<double> mid_t, mid_v;
  for (int k = 0; k < kStretches; ++k) {
    std::vector<double> in_t, in_v;
    for (size_t i = 0; i < t.size(); ++i) {
      const int stretch =
          std::min(kStretches - 1, static_cast<int>(kStretches * (t[i] - t0) / span));
      if (stretch == k) in_t.push_back(t[i]), in_v.push_back(v[i]);
    }
    if (in_t.empty()) continue;
    mid_t.push_back(UpperMedian(&in_t));
    mid_v.push_back(UpperMedian(&in_v));
  }
  const size_t n = mid_t.size();
  double mt = 0.0, mv = 0.0;
  for (size_t k = 0; k < n; ++k) mt += mid_t[k] / n, mv += mid_v[k] / n;
  double stt = 0.0, stv = 0.0;
  for (size_t k = 0; k < n; ++k) {
    stt += (mid_t[k] - mt) * (mid_t[k] - mt);
    stv += (mid_t[k] - mt) * (mid_v[k] - mv);
  }
  WallHeading out;
  const double slope = stt > 0.0 ? stv / stt : 0.0;
  out.drift_rad = slope * span;
  double ssr = 0.0;
  for (size_t k = 0; k < n; ++k) ssr += std::pow(mid_v[k] - mv - slope * (mid_t[k] - mt), 2);
  out.drift_stddev_rad = n > 2 && stt > 0.0 ? std::sqrt(ssr / (n - 2) / stt) * span : HUGE_VAL;
  std::vector<double> deviation;
  for (size_t i = 0; i < t.size(); ++i) {
    deviation.push_back(std::abs(v[i] - mv - slope * (t[i] - mt)));
  }
  out.scatter_rad = 1.4826 * UpperMedian(&deviation);
  return out;
}

}  // namespace

std::optional<double> WallDirectionRad(const LaserScan& scan) {
  const int n = static_cast<int>(scan.ranges_m.size());
  const double increment = std::abs(scan.angle_increment_rad);
  if (n < 3 || !(increment > 0.0)) return std::nullopt;
  const auto point = [&](int i) {
    const double a = scan.BeamAngle(i), r = scan.ranges_m[i];
    return Eigen::Vector2d(r * std::cos(a), r * std::sin(a));
  };
  double c = 0.0, s = 0.0;
  for (int i = 0; i + 2 < n; ++i) {
    if (!scan.IsReturn(i)) continue;
    // Beams about kChordM apart at this range (2 to 20 beams).
    const int half = std::clamp(
        static_cast<int>(std::lround(0.5 * kChordM / (scan.ranges_m[i] * increment))), 1, 10);
    const int j = i + 2 * half, m = i + half;
    if (j >= n || !scan.IsReturn(j) || !scan.IsReturn(m)) continue;
    const Eigen::Vector2d p = point(i), chord = point(j) - p, off = point(m) - p;
    const double length = chord.norm();
    if (length < kMinChordM || length > kMaxChordM) continue;
    // Straight: the middle beam within 1 cm and 5 % of the chord's length of it.
    if (std::abs(off.x() * chord.y() - off.y() * chord.x()) / length > 0.01 + 0.05 * length) {
      continue;
    }
    const double a = std::atan2(chord.y(), chord.x());
    c += length * std::cos(4.0 * a);
    s += length * std::sin(4.0 * a);
  }
  if (std::hypot(c, s) < kMinWallsM) return std::nullopt;
  return std::atan2(s, c) / 4.0;
}

WallCheck CheckAgainstWalls(const std::vector<LaserScan>& scans, bool mirrored,
                            const std::vector<EncoderSample>& wheels,
                            const OdometryParams& calibrated,
                            const std::optional<OdometryParams>& nominal,
                            double scan_time_offset_s) {
  WallCheck out;
  out.scans = static_cast<int>(scans.size());
  if (scans.size() < 2 * kStretches || wheels.size() < 2) return out;
  std::vector<Bearing> bearings;
  for (const LaserScan& scan : scans) {
    const double t = scan.stamp_s + scan_time_offset_s;
    if (t < wheels.front().t_s || t > wheels.back().t_s) continue;
    if (const std::optional<double> wall = WallDirectionRad(scan)) {
      bearings.push_back({t, mirrored ? -*wall : *wall});
    }
  }
  out.scans_with_walls = static_cast<int>(bearings.size());
  if (bearings.size() < 2 * kStretches) return out;
  out.duration_s = bearings.back().t_s - bearings.front().t_s;
  out.calibrated = Trend(bearings, wheels, calibrated);
  if (nominal) out.nominal = Trend(bearings, wheels, *nominal);
  out.right_angled =
      2 * out.scans_with_walls >= out.scans && out.calibrated.scatter_rad <= kMaxScatterRad;
  return out;
}

}  // namespace calib
