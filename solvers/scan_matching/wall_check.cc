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

// The walls' direction in the building under `odometry`'s heading, scan by scan, unwrapped
// against the median of the last scans' (one scan's odd direction must not turn all after it by
// 90°).
std::vector<double> Directions(const std::vector<Bearing>& bearings,
                               const std::vector<EncoderSample>& wheels,
                               const OdometryParams& odometry) {
  WheelHeading heading(wheels);
  std::vector<double> v, recent;
  for (const Bearing& b : bearings) {
    const double direction = Wrap90(heading.At(b.t_s, odometry) + b.wall_rad);
    recent.assign(v.end() - std::min<size_t>(v.size(), kUnwrapScans), v.end());
    const double reference = recent.empty() ? direction : UpperMedian(&recent);
    v.push_back(reference + Wrap90(direction - reference));
  }
  return v;
}

// The line through the medians (time, direction) of kStretches equal stretches of the log.
struct Line {
  double t_mean = 0.0, v_mean = 0.0, slope = 0.0, slope_stddev = 0.0;
};

Line StretchTrend(const std::vector<double>& t, const std::vector<double>& v) {
  const double t0 = t.front(), span = t.back() - t.front();
  std::vector<std::vector<double>> in_t(kStretches), in_v(kStretches);
  for (size_t i = 0; i < t.size(); ++i) {
    const int k = std::min(kStretches - 1, static_cast<int>(kStretches * (t[i] - t0) / span));
    in_t[k].push_back(t[i]);
    in_v[k].push_back(v[i]);
  }
  std::vector<double> mt, mv;
  for (int k = 0; k < kStretches; ++k) {
    if (in_t[k].empty()) continue;
    mt.push_back(UpperMedian(&in_t[k]));
    mv.push_back(UpperMedian(&in_v[k]));
  }
  const size_t n = mt.size();
  Line line;
  for (size_t k = 0; k < n; ++k) line.t_mean += mt[k] / n, line.v_mean += mv[k] / n;
  double stt = 0.0, stv = 0.0;
  for (size_t k = 0; k < n; ++k) {
    stt += (mt[k] - line.t_mean) * (mt[k] - line.t_mean);
    stv += (mt[k] - line.t_mean) * (mv[k] - line.v_mean);
  }
  if (n < 3 || !(stt > 0.0)) return line;
  line.slope = stv / stt;
  double ssr = 0.0;
  for (size_t k = 0; k < n; ++k) {
    ssr += std::pow(mv[k] - line.v_mean - line.slope * (mt[k] - line.t_mean), 2);
  }
  line.slope_stddev = std::sqrt(ssr / (n - 2) / stt);
  return line;
}

WallHeading Trend(const std::vector<Bearing>& bearings, const std::vector<EncoderSample>& wheels,
                  const OdometryParams& odometry) {
  const std::vector<double> v = Directions(bearings, wheels, odometry);
  std::vector<double> t;
  for (const Bearing& b : bearings) t.push_back(b.t_s);
  const Line line = StretchTrend(t, v);
  const double span = t.back() - t.front();
  std::vector<double> deviation;
  for (size_t i = 0; i < t.size(); ++i) {
    deviation.push_back(std::abs(v[i] - line.v_mean - line.slope * (t[i] - line.t_mean)));
  }
  return {line.slope * span, line.slope_stddev * span, 1.4826 * UpperMedian(&deviation)};
}

// The drift's σ through the wheels' covariance, by central differences of the drift in r_l, r_r
// and b (steps of 10⁻⁴ of each).
double CalibrationStddev(const std::vector<Bearing>& bearings,
                         const std::vector<EncoderSample>& wheels, const OdometryParams& odometry,
                         const Eigen::Matrix3d& covariance) {
  const Eigen::Vector3d p(odometry.left_radius_m, odometry.right_radius_m, odometry.wheelbase_m);
  Eigen::Vector3d gradient;
  for (int i = 0; i < 3; ++i) {
    const double step = 1e-4 * p(i);
    Eigen::Vector3d lo = p, hi = p;
    lo(i) -= step;
    hi(i) += step;
    const double up = Trend(bearings, wheels, {hi(0), hi(1), hi(2)}).drift_rad;
    const double down = Trend(bearings, wheels, {lo(0), lo(1), lo(2)}).drift_rad;
    gradient(i) = (up - down) / (2.0 * step);
  }
  return std::sqrt(std::max(0.0, gradient.dot(covariance * gradient)));
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
                            const std::optional<OdometryParams>& nominal, double scan_time_offset_s,
                            const std::optional<Eigen::Matrix3d>& covariance) {
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
  const double duration_s = bearings.back().t_s - bearings.front().t_s;
  if (!(duration_s > 0.0)) return out;  // One instant: no trend.
  out.duration_s = duration_s;
  out.calibrated = Trend(bearings, wheels, calibrated);
  if (covariance) {
    out.calibrated.calibration_stddev_rad =
        CalibrationStddev(bearings, wheels, calibrated, *covariance);
  }
  if (nominal) out.nominal = Trend(bearings, wheels, *nominal);
  out.right_angled =
      2 * out.scans_with_walls >= out.scans && out.calibrated.scatter_rad <= kMaxScatterRad;
  return out;
}

}  // namespace calib
