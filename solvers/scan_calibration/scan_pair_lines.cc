#include <calib/solvers/scan_calibration/scan_pair_lines.h>
#include <calib/solvers/scan_matching/scan_points.h>

#include <algorithm>
#include <cmath>

namespace calib {
namespace {

Eigen::Vector2d Apply(const Pose2d& pose, const Eigen::Vector2d& p) {
  return Compose(pose, Pose2d(p.x(), p.y(), 0.0)).head<2>();
}

Eigen::Vector2d Rotate(double angle, const Eigen::Vector2d& v) {
  const double c = std::cos(angle), s = std::sin(angle);
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}

// The beam of a scan point in the pair's geometry, added on first use (located at its time
// shifted by the geometry's offset).
int BeamOf(const PairTimeline& timeline, const LaserScan& scan, double first_beam_s,
           const ScanPoints& raw, int point, std::vector<int>* beam_of_point, ScanPairGeometry* g) {
  int& beam = (*beam_of_point)[point];
  if (beam >= 0) return beam;
  ScanPairGeometry::Beam b;
  timeline.Locate(first_beam_s + raw.beams[point] * scan.time_increment_s + g->located_offset_s,
                  &b.step, &b.fraction);
  if (b.step < static_cast<int>(timeline.steps.size())) {
    b.fraction_per_s = 1.0 / timeline.StepSeconds(b.step);
  }
  b.point_m = raw.points_m[point];
  beam = static_cast<int>(g->beams.size());
  g->beams.push_back(b);
  return beam;
}

// The reference return whose polar angle is nearest to the point's, among the beams around the
// one it looks along: unlike the nearest point, the choice does not depend on the reference's
// range noise, which would pull every line towards the current point (at 1081 beams and 1 cm of
// noise the nearest point made the distances 30 % smaller than the noise). −1 when none.
int ReturnAlongBeam(const ScanPoints& ref, double phi_rad) {
  const int n = ref.NumBeams();
  // Beyond π from angle_min (a 270° scan's last third) the wrapped offset alone found no beam.
  const int k = ref.NearestBeam(phi_rad);
  int best = -1;
  double best_delta = std::abs(ref.angle_increment_rad) * 2.5;
  for (int d = -2; d <= 2; ++d) {
    int beam = k + d;
    if (ref.full_circle) beam = ((beam % n) + n) % n;
    if (beam < 0 || beam >= n || ref.point_of_beam[beam] < 0) continue;
    const double delta = std::abs(WrapAngle(ref.beam_angle_rad[beam] - phi_rad));
    if (delta < best_delta) {
      best_delta = delta;
      best = ref.point_of_beam[beam];
    }
  }
  return best;
}

// From point a along the beams in `step`, the first return at least min_segment_length_m away,
// with no depth jump (max_segment_length_m) between consecutive returns; −1 when none.
int SegmentEnd(const ScanPoints& ref, int a, int step, const CorrespondenceOptions& o) {
  const int n = ref.NumBeams();
  const double max2 = o.max_segment_length_m * o.max_segment_length_m;
  const double min2 = o.min_segment_length_m * o.min_segment_length_m;
  int previous = a;
  for (int k = 1; k < n; ++k) {
    int beam = ref.beams[a] + step * k;
    if (ref.full_circle) beam = ((beam % n) + n) % n;
    if (beam < 0 || beam >= n || k > 60) return -1;
    const int j = ref.point_of_beam[beam];
    if (j < 0) continue;
    if ((ref.points_m[j] - ref.points_m[previous]).squaredNorm() > max2) return -1;
    if ((ref.points_m[j] - ref.points_m[a]).squaredNorm() >= min2) return j;
    previous = j;
  }
  return -1;
}

// The turn from direction `before` to direction `after` exceeds max_bend_rad.
bool Bends(const Eigen::Vector2d& before, const Eigen::Vector2d& after, double max_bend_rad) {
  const double cross = before.x() * after.y() - before.y() * after.x();
  return std::abs(std::atan2(cross, before.dot(after))) > max_bend_rad;
}

// The reference segment from return a to return b spans a corner, and its line is neither wall:
// it turns at its middle return, or it leaves the line that the returns before a (a segment on
// a's other side) follow, by more than max_bend_rad (at 1 cm of noise the directions of these
// 0.12–0.25 m chords scatter by 0.06–0.11 rad). A segment across a full circle's seam is not
// checked at its middle.
bool SpansCorner(const ScanPoints& ref, int a, int b, const CorrespondenceOptions& o) {
  const Eigen::Vector2d& pa = ref.points_m[a];
  const int behind = SegmentEnd(ref, a, b > a ? -1 : 1, o);
  if (behind >= 0 && Bends(pa - ref.points_m[behind], ref.points_m[b] - pa, o.max_bend_rad)) {
    return true;
  }
  if (std::abs(b - a) < 2 || std::abs(b - a) > ref.NumPoints() / 2) return false;
  const Eigen::Vector2d& pm = ref.points_m[(a + b) / 2];
  return Bends(pm - pa, ref.points_m[b] - pm, o.max_bend_rad);
}

void FindBeamCorrespondences(const ScanPoints& ref, const std::vector<Eigen::Vector2d>& points,
                             const CorrespondenceOptions& o, std::vector<Correspondence>* out) {
  out->clear();
  for (size_t i = 0; i < points.size(); ++i) {
    const double phi = std::atan2(points[i].y(), points[i].x());
    const int a = ReturnAlongBeam(ref, phi);
    if (a < 0 || (ref.points_m[a] - points[i]).norm() > o.max_distance_m) continue;
    const int toward =
        WrapAngle(phi - ref.beam_angle_rad[ref.beams[a]]) * ref.angle_increment_rad >= 0.0 ? 1 : -1;
    int b = SegmentEnd(ref, a, toward, o);
    if (b < 0 || SpansCorner(ref, a, b, o)) b = SegmentEnd(ref, a, -toward, o);
    if (b < 0 || SpansCorner(ref, a, b, o)) continue;
    out->push_back(Correspondence{static_cast<int>(i), a, b});
  }
}

}  // namespace

Status FindPairLines(const ScanPointInput& input, const LaserCalibration& c, double time_offset_s,
                     const ScanPointOptions& options, ScanPair* pair) {
  const LaserScan& ref = *input.scans[pair->reference];
  const LaserScan& cur = *input.scans[pair->current];
  // Beam 0's time as given, and shifted by the sensor's time offset.
  const double first_ref = input.first_beam_time_s[pair->reference];
  const double first_cur = input.first_beam_time_s[pair->current];
  const double t_ref = first_ref + time_offset_s, t_cur = first_cur + time_offset_s;
  const std::vector<Pose2d> knots = KnotPoses(pair->timeline, c.odometry);
  // Everything in the laser frame at the reference's stamp (its beam 0): the reference de-skewed
  // there for the search (the residual places its beams exactly), the current scan's points
  // moved there beam by beam.
  const Pose2d stamp_pose = LaserMotion(pair->timeline, knots, c, t_ref);
  const auto from_stamp = [&](double t) {
    return Between(stamp_pose, LaserMotion(pair->timeline, knots, c, t));
  };
  ScanPointsOptions deskew;
  const double ref_sweep_s = ref.SweepSeconds();
  if (ref_sweep_s > 0.0) {  // One piece per encoder step, as the matcher de-skews.
    const double min_step_s = 1e-6 * ref_sweep_s, end_s = t_ref + ref_sweep_s;
    std::vector<double> knots{t_ref};
    for (const double t : pair->timeline.knot_time_s) {
      if (t > knots.back() + min_step_s && t < end_s - min_step_s) knots.push_back(t);
    }
    knots.push_back(end_s);
    SweepMotion sweep{{}, {}};
    for (size_t k = 0; k + 1 < knots.size(); ++k) {
      sweep.start_s.push_back(knots[k] - t_ref);
      sweep.velocity.push_back(Log(Between(from_stamp(knots[k]), from_stamp(knots[k + 1]))) /
                               (knots[k + 1] - knots[k]));
    }
    deskew.sweep = sweep;
  } else if (ref_sweep_s < 0.0) {  // A mirrored scan's beams run back in time from its stamp.
    deskew.sweep = SweepMotion::Constant(Log(from_stamp(t_ref + ref_sweep_s)) / ref_sweep_s);
  }
  CALIB_ASSIGN_OR_RETURN(const ScanPoints ref_points, MakeScanPoints(ref, deskew));
  CALIB_ASSIGN_OR_RETURN(const ScanPoints ref_raw, MakeScanPoints(ref));
  CALIB_ASSIGN_OR_RETURN(const ScanPoints cur_raw, MakeScanPoints(cur));
  std::vector<Eigen::Vector2d> cur_in_ref(cur_raw.points_m.size());
  for (size_t i = 0; i < cur_in_ref.size(); ++i) {
    const double t = t_cur + cur_raw.beams[i] * cur.time_increment_s;
    cur_in_ref[i] = Apply(from_stamp(t), cur_raw.points_m[i]);
  }
  std::vector<Correspondence> found;
  FindBeamCorrespondences(ref_points, cur_in_ref, options.correspondence, &found);
  const double cur_angle = from_stamp(t_cur + cur.SweepSeconds() / 2)(2);
  ScanPairGeometry& g = pair->geometry;
  g = ScanPairGeometry();
  g.steps = pair->timeline.steps;
  g.located_offset_s = time_offset_s;
  pair->variance_factor.clear();
  std::vector<int> ref_beam(ref_raw.points_m.size(), -1), cur_beam(cur_raw.points_m.size(), -1);
  const size_t stride = std::max<size_t>(
      1, (found.size() + options.max_lines_per_pair - 1) / std::max(1, options.max_lines_per_pair));
  for (size_t k = 0; k < found.size(); k += stride) {
    const Correspondence& f = found[k];
    const Eigen::Vector2d& qa = ref_points.points_m[f.reference_a];
    const Eigen::Vector2d along = ref_points.points_m[f.reference_b] - qa;
    const double length2 = along.squaredNorm();
    if (!(length2 > 0.0)) continue;
    const Eigen::Vector2d n = Eigen::Vector2d(-along.y(), along.x()) / std::sqrt(length2);
    const double alpha = (cur_in_ref[f.current] - qa).dot(along) / length2;
    const double dc = n.dot(Rotate(cur_angle, cur_raw.directions[f.current]));
    const double da = (1.0 - alpha) * n.dot(ref_points.directions[f.reference_a]);
    const double db = alpha * n.dot(ref_points.directions[f.reference_b]);
    ScanPairGeometry::Line line;
    line.current = BeamOf(pair->timeline, cur, first_cur, cur_raw, f.current, &cur_beam, &g);
    line.a = BeamOf(pair->timeline, ref, first_ref, ref_raw, f.reference_a, &ref_beam, &g);
    line.b = BeamOf(pair->timeline, ref, first_ref, ref_raw, f.reference_b, &ref_beam, &g);
    g.lines.push_back(line);
    pair->variance_factor.push_back(std::max(dc * dc + da * da + db * db, 1e-6));
  }
  pair->distance_m.assign(g.lines.size(), 0.0);
  if (g.lines.empty()) return Status::Ok();
  const LaserParamVector v = c.ToVector();
  const double* parameters[3] = {v.data(), v.data() + 3, &time_offset_s};
  const ScanPairResidual distances(&g);
  distances(parameters, pair->distance_m.data());
  return Status::Ok();
}

int WeighPairLines(double range_sigma_m, const ScanPointOptions& options, ScanPair* pair) {
  ScanPairGeometry& g = pair->geometry;
  size_t kept = 0;
  const double c2 = options.loss_scale_sigmas * options.loss_scale_sigmas;
  for (size_t i = 0; i < g.lines.size(); ++i) {
    const double scale_m = range_sigma_m * std::sqrt(pair->variance_factor[i]);
    const double z = pair->distance_m[i] / scale_m;
    if (!(std::abs(z) <= options.gate_sigmas)) continue;
    g.lines[kept] = g.lines[i];
    g.lines[kept].weight = std::sqrt(1.0 / (1.0 + z * z / c2)) / scale_m;
    pair->variance_factor[kept] = pair->variance_factor[i];
    pair->distance_m[kept] = pair->distance_m[i];
    ++kept;
  }
  g.lines.resize(kept);
  pair->variance_factor.resize(kept);
  pair->distance_m.resize(kept);
  return static_cast<int>(kept);
}

}  // namespace calib
