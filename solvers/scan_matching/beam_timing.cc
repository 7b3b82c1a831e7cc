#include <calib/core/order_statistic.h>
#include <calib/core/text_format.h>
#include <calib/solvers/scan_matching/beam_timing.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

namespace calib {
namespace {

// Two neighbouring points farther apart than this (and the beams' arc) lie across a depth jump,
// not on one surface.
constexpr double kSegmentM = 0.3;

// The scans' period: the median step between their stamps.
double MedianStep(const std::vector<LaserScan>& scans) {
  std::vector<double> steps;
  for (size_t i = 1; i < scans.size(); ++i)
    steps.push_back(scans[i].stamp_s - scans[i - 1].stamp_s);
  return UpperMedian(&steps);
}

std::string Milliseconds(double seconds) { return Format("%.4g ms", 1e3 * seconds); }

BeamTiming Timing(bool reversed, double increment_s, const std::string& source) {
  BeamTiming t;
  t.reversed = reversed;
  t.time_increment_s = increment_s;
  t.description = std::string(reversed ? "in reverse order" : "in listed order") + ", " +
                  Milliseconds(increment_s) + " apart (" + source + ")";
  return t;
}

// The plausible timings: the driver's, its beams reversed, and one rotation per scan period
// either way. Duplicates (within 10 %) are left out; the driver's comes first. (No sweep at all
// cannot be judged: its ends meet without overlapping.)
std::vector<BeamTiming> Candidates(double recorded_s, double rotation_s) {
  std::vector<BeamTiming> out{Timing(false, recorded_s, "the driver's time_increment")};
  const auto add = [&](bool reversed, double increment_s, const std::string& source) {
    for (const BeamTiming& c : out) {
      const double scale = std::max(c.time_increment_s, increment_s);
      if (c.reversed == reversed && std::abs(c.time_increment_s - increment_s) <= 0.1 * scale) {
        return;
      }
    }
    out.push_back(Timing(reversed, increment_s, source));
  };
  if (recorded_s > 0.0) add(true, recorded_s, "the driver's time_increment");
  if (rotation_s > 0.0) {
    add(false, rotation_s, "one turn per scan period");
    add(true, rotation_s, "one turn per scan period");
  }
  return out;
}

// The scans (indices) whose sensor turns most over one scan period through `robot`, half of
// max_scans each way, each turning at least min_turn_rad. Both ways: only the turns with the
// spin make a sweep's ends overlap, and which way that is depends on the timing under test.
std::vector<size_t> TurningScans(const std::vector<LaserScan>& scans,
                                 const std::vector<EncoderSample>& encoders,
                                 const WheelsAndMounting& robot, const SweepStarts& starts,
                                 double period_s, const BeamTimingOptions& options) {
  std::vector<std::pair<double, size_t>> turns[2];  // Left, right; the largest first after sorting.
  for (size_t i = 0; i < scans.size(); ++i) {
    const double t = starts(i, scans[i].stamp_s);
    const double turn = SensorMotionBetween(encoders, t, t + period_s, robot)(2);
    if (std::abs(turn) >= options.min_turn_rad) turns[turn < 0.0].emplace_back(-std::abs(turn), i);
  }
  std::vector<size_t> chosen;
  for (auto& way : turns) {
    const size_t kept =
        std::min(way.size(), static_cast<size_t>(std::max(options.max_scans / 2, 0)));
    std::partial_sort(way.begin(), way.begin() + kept, way.end());
    for (size_t k = 0; k < kept; ++k) chosen.push_back(way[k].second);
  }
  return chosen;
}

// The de-skewed points of beams [from, to) of `points`, in beam order.
std::vector<Eigen::Vector2d> BeamPoints(const ScanPoints& points, int from, int to) {
  std::vector<Eigen::Vector2d> out;
  for (int i = from; i < to; ++i) {
    if (points.point_of_beam[i] >= 0) out.push_back(points.points_m[points.point_of_beam[i]]);
  }
  return out;
}

// Adds to *sum the capped distance of each of `points` that `other` covers in polar angle (seen
// from the stamp's sensor origin) to the segment of `other` between the two points bracketing it,
// and to *count their number. A point with no bracketing segment (a gap between the ends, a
// depth jump) is not compared.
void AddBracketed(const std::vector<Eigen::Vector2d>& other,
                  const std::vector<Eigen::Vector2d>& points, double max_step_rad, double cap,
                  double* sum, int* count) {
  std::vector<double> polar;
  for (const Eigen::Vector2d& q : other) polar.push_back(std::atan2(q.y(), q.x()));
  for (const Eigen::Vector2d& p : points) {
    const double phi = std::atan2(p.y(), p.x());
    for (size_t j = 0; j + 1 < other.size(); ++j) {
      const double a = WrapAngle(polar[j] - phi), b = WrapAngle(polar[j + 1] - phi);
      if (a * b > 0.0 || std::abs(a) > max_step_rad || std::abs(b) > max_step_rad) continue;
      const Eigen::Vector2d step = other[j + 1] - other[j];
      const double spacing = other[j].norm() * max_step_rad;  // Three beams' arc at this range.
      if (!(step.norm() < kSegmentM + spacing) || !(step.norm() > 0.0)) break;
      const Eigen::Vector2d u = step.normalized(), d = p - other[j];
      *sum += std::min(std::abs(u.x() * d.y() - u.y() * d.x()), cap);
      ++*count;
      break;
    }
  }
}

// Where a full circle's sweep closes, its first and last measured beams look the same way a
// sweep apart (and, turning with the spin, overlap by the turn): de-skewed right, the two ends
// continue each other's walls; de-skewed wrong, they are turned apart by the motion left over.
// Adds each end's points held to the other end's segments (capped distances) to *sum and their
// number to *count.
void AddSeam(const LaserScan& listed, const BeamTiming& timing,
             const std::vector<EncoderSample>& encoders, const WheelsAndMounting& robot,
             double start_s, const BeamTimingOptions& options, double* sum, int* count) {
  const LaserScan scan = WithBeamTiming(listed, timing);
  const int n = static_cast<int>(scan.ranges_m.size());
  const double increment = std::abs(scan.angle_increment_rad);
  const int k = std::max(3, static_cast<int>(std::lround(options.seam_rad / increment)));
  if (n < 4 * k) return;
  ScanPointsOptions deskew;
  if (scan.SweepSeconds() > 0.0) {
    deskew.sweep = SweepMotionOver(encoders, start_s, scan.SweepSeconds(), robot);
  }
  const StatusOr<ScanPoints> points = MakeScanPoints(scan, deskew);
  if (!points.ok() || !points->full_circle) return;
  const std::vector<Eigen::Vector2d> first = BeamPoints(*points, 0, k);
  const std::vector<Eigen::Vector2d> last = BeamPoints(*points, n - k, n);
  AddBracketed(last, first, 3.0 * increment, options.cap_m, sum, count);
  AddBracketed(first, last, 3.0 * increment, options.cap_m, sum, count);
}

// The candidate the seams choose: the driver's (0) unless another clearly beats it. Where the
// driver's could be judged, its distance must fall by clear_ratio; where it could not (a sweep
// too short for its seams to overlap), the best must beat every other judged one by clear_ratio
// and close its seams to within half the cap.
size_t Best(const std::vector<std::pair<BeamTiming, double>>& candidates,
            const BeamTimingOptions& options) {
  if (candidates.empty()) return 0;
  size_t best = 0;
  for (size_t c = 1; c < candidates.size(); ++c) {
    if (candidates[c].second < candidates[best].second) best = c;
  }
  const double best_m = candidates[best].second, recorded_m = candidates.front().second;
  if (best == 0 || !std::isfinite(best_m)) return 0;
  if (std::isfinite(recorded_m)) return best_m < options.clear_ratio * recorded_m ? best : 0;
  if (!(best_m < 0.5 * options.cap_m)) return 0;
  for (size_t c = 1; c < candidates.size(); ++c) {
    if (c != best && !(best_m < options.clear_ratio * candidates[c].second)) return 0;
  }
  return best;
}

}  // namespace

LaserScan WithBeamTiming(const LaserScan& scan, const BeamTiming& timing) {
  LaserScan out = scan;
  out.time_increment_s = timing.time_increment_s;
  if (!timing.reversed || scan.ranges_m.empty()) return out;
  const double last = static_cast<double>(scan.ranges_m.size()) - 1.0;
  out.angle_min_rad = scan.angle_min_rad + last * scan.angle_increment_rad;
  out.angle_increment_rad = -scan.angle_increment_rad;
  std::reverse(out.ranges_m.begin(), out.ranges_m.end());
  std::reverse(out.intensities.begin(), out.intensities.end());
  return out;
}

BeamTimingCheck CheckBeamTiming(const std::vector<LaserScan>& scans,
                                const std::vector<EncoderSample>& encoders,
                                const WheelsAndMounting& robot, const SweepStarts& starts,
                                const std::string& name, const BeamTimingOptions& options) {
  BeamTimingCheck check;
  if (scans.size() < 2 || encoders.size() < 2 || !robot.known()) return check;
  std::vector<double> increments;
  for (const LaserScan& scan : scans) increments.push_back(scan.time_increment_s);
  const double recorded_s = std::max(UpperMedian(&increments), 0.0);
  const double period_s = MedianStep(scans);
  const double rotation_s =
      period_s > 0.0 ? period_s * std::abs(scans.front().angle_increment_rad) / (2.0 * M_PI) : 0.0;
  const std::vector<BeamTiming> candidates = Candidates(recorded_s, rotation_s);
  check.recorded = check.chosen = candidates.front();
  const std::vector<size_t> turning =
      TurningScans(scans, encoders, robot, starts, period_s, options);
  check.scans = static_cast<int>(turning.size());
  if (check.scans < options.min_scans) return check;
  for (const BeamTiming& timing : candidates) {
    double sum = 0.0;
    int points = 0;
    for (const size_t i : turning)
      AddSeam(scans[i], timing, encoders, robot, starts(i, scans[i].stamp_s), options, &sum,
              &points);
    // Too few compared points (no full circle, gaps at every seam): this timing is not judged.
    check.candidates.emplace_back(timing, points >= options.min_points
                                              ? sum / points
                                              : std::numeric_limits<double>::infinity());
  }
  const size_t best = Best(check.candidates, options);
  if (best == 0) return check;
  const double recorded_m = check.candidates.front().second, best_m = check.candidates[best].second;
  check.changed = true;
  check.chosen = check.candidates[best].first;
  check.warning = Format(
      "%s: the beams' timing is not what the driver says: de-skewed under each plausible timing, "
      "the sweeps of the %d fastest turns close best (their first and last beams continue each "
      "other's walls) with the beams measured %s (mean capped point-to-line distance %.1f mm, "
      "against %s with the driver's time_increment %.3g s in listed order), and calib "
      "de-skews every sweep so; a driver that lists its beams against "
      "the order they were measured in (the LDS-01's hls_lfcd_lds_driver) or gives too small a "
      "time_increment (the same driver's) biases a calibration that trusts it",
      name.c_str(), check.scans, check.chosen.description.c_str(), 1e3 * best_m,
      std::isfinite(recorded_m) ? Format("%.1f mm", 1e3 * recorded_m).c_str()
                                : "ends that never overlap",
      recorded_s);
  return check;
}

}  // namespace calib
