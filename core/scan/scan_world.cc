#include <calib/core/random.h>
#include <calib/core/scan/scan_world.h>
#include <calib/core/text_number.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace calib {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
// A ray through a shared wall end must hit one of the two walls despite rounding.
constexpr double kEndSlack = 1e-9;
constexpr int kMaxCellsPerAxis = 2048;

double Cross(const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
  return u.x() * v.y() - u.y() * v.x();
}

// p + t·d = a + u·(b − a): t = (a − p)×e / d×e, u = (a − p)×d / d×e.
double HitDistance(const WallSegment& s, const Eigen::Vector2d& p, const Eigen::Vector2d& d) {
  const Eigen::Vector2d e = s.b - s.a;
  const double denom = Cross(d, e);
  if (denom == 0.0) return kInfinity;  // Parallel: a grazing ray sees no wall.
  const Eigen::Vector2d w = s.a - p;
  const double t = Cross(w, e) / denom;
  const double u = Cross(w, d) / denom;
  if (t < 0.0 || u < -kEndSlack || u > 1.0 + kEndSlack) return kInfinity;
  return t;
}

double PointSegmentDistance(const Eigen::Vector2d& p, const WallSegment& s) {
  const Eigen::Vector2d e = s.b - s.a;
  const double u = std::clamp((p - s.a).dot(e) / e.squaredNorm(), 0.0, 1.0);
  return (s.a + u * e - p).norm();
}

}  // namespace

ScanWorld::ScanWorld(std::vector<WallSegment> segments) {
  for (const WallSegment& s : segments) {
    if (s.a.allFinite() && s.b.allFinite() && s.a != s.b) segments_.push_back(s);
  }
  if (segments_.empty()) return;
  Eigen::Vector2d lo = segments_[0].a, hi = segments_[0].a;
  for (const WallSegment& s : segments_) {
    lo = lo.cwiseMin(s.a).cwiseMin(s.b);
    hi = hi.cwiseMax(s.a).cwiseMax(s.b);
  }
  const Eigen::Vector2d size = (hi - lo).cwiseMax(1e-6);
  // About four cells per segment, no smaller than 0.25 m, at most kMaxCellsPerAxis a side.
  cell_m_ = std::max(0.25, std::sqrt(size.x() * size.y() / (4.0 * segments_.size())));
  cell_m_ = std::max(cell_m_, size.maxCoeff() / kMaxCellsPerAxis);
  grid_min_ = lo;
  nx_ = std::min(kMaxCellsPerAxis, static_cast<int>(size.x() / cell_m_) + 1);
  ny_ = std::min(kMaxCellsPerAxis, static_cast<int>(size.y() / cell_m_) + 1);
  // Each segment goes into the cells of its bounding box (exact for the axis-aligned walls).
  std::vector<std::pair<int, int>> entries;
  for (size_t i = 0; i < segments_.size(); ++i) {
    const Eigen::Vector2d a = (segments_[i].a.cwiseMin(segments_[i].b) - lo) / cell_m_;
    const Eigen::Vector2d b = (segments_[i].a.cwiseMax(segments_[i].b) - lo) / cell_m_;
    const int x0 = std::clamp(static_cast<int>(a.x()) - (a.x() == std::floor(a.x())), 0, nx_ - 1);
    const int y0 = std::clamp(static_cast<int>(a.y()) - (a.y() == std::floor(a.y())), 0, ny_ - 1);
    const int x1 = std::clamp(static_cast<int>(b.x()), 0, nx_ - 1);
    const int y1 = std::clamp(static_cast<int>(b.y()), 0, ny_ - 1);
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) entries.emplace_back(y * nx_ + x, static_cast<int>(i));
    }
  }
  std::sort(entries.begin(), entries.end());
  cell_start_.assign(static_cast<size_t>(nx_) * ny_ + 1, 0);
  for (const auto& [cell, segment] : entries) ++cell_start_[cell + 1];
  for (size_t c = 1; c < cell_start_.size(); ++c) cell_start_[c] += cell_start_[c - 1];
  cell_segments_.reserve(entries.size());
  for (const auto& entry : entries) cell_segments_.push_back(entry.second);
}

double ScanWorld::CellHits(int cell, const Eigen::Vector2d& origin,
                           const Eigen::Vector2d& direction, double best) const {
  for (int k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
    best = std::min(best, HitDistance(segments_[cell_segments_[k]], origin, direction));
  }
  return best;
}

double ScanWorld::CastRay(const Eigen::Vector2d& origin, double angle_rad,
                          double max_range_m) const {
  if (nx_ == 0 || !origin.allFinite() || !std::isfinite(angle_rad)) return kInfinity;
  const Eigen::Vector2d d(std::cos(angle_rad), std::sin(angle_rad));
  // Clip the ray to the grid's box (slabs).
  const Eigen::Vector2d hi = grid_min_ + cell_m_ * Eigen::Vector2d(nx_, ny_);
  double t_in = 0.0, t_out = max_range_m;
  for (int k = 0; k < 2; ++k) {
    if (d(k) == 0.0) {
      if (origin(k) < grid_min_(k) || origin(k) > hi(k)) return kInfinity;
      continue;
    }
    double t0 = (grid_min_(k) - origin(k)) / d(k), t1 = (hi(k) - origin(k)) / d(k);
    if (t0 > t1) std::swap(t0, t1);
    t_in = std::max(t_in, t0);
    t_out = std::min(t_out, t1);
  }
  if (t_in > t_out) return kInfinity;
  const Eigen::Vector2d start = (origin + t_in * d - grid_min_) / cell_m_;
  int ix = std::clamp(static_cast<int>(start.x()), 0, nx_ - 1);
  int iy = std::clamp(static_cast<int>(start.y()), 0, ny_ - 1);
  const int step_x = d.x() > 0 ? 1 : -1, step_y = d.y() > 0 ? 1 : -1;
  // Ray parameter of the next vertical / horizontal cell border, and between two of them.
  const auto border = [&](int i, int step, int k) {
    if (d(k) == 0.0) return kInfinity;
    const double edge = grid_min_(k) + cell_m_ * (i + (step > 0 ? 1 : 0));
    return (edge - origin(k)) / d(k);
  };
  double next_x = border(ix, step_x, 0), next_y = border(iy, step_y, 1);
  const double delta_x = d.x() == 0.0 ? kInfinity : cell_m_ / std::abs(d.x());
  const double delta_y = d.y() == 0.0 ? kInfinity : cell_m_ / std::abs(d.y());
  double best = kInfinity;
  while (true) {
    best = CellHits(iy * nx_ + ix, origin, d, best);
    const double cell_exit = std::min(next_x, next_y);
    // A hit inside this cell (or before it) cannot be beaten by a later cell.
    if (best <= cell_exit || cell_exit > t_out) break;
    if (next_x < next_y) {
      ix += step_x;
      next_x += delta_x;
    } else {
      iy += step_y;
      next_y += delta_y;
    }
    if (ix < 0 || iy < 0 || ix >= nx_ || iy >= ny_) break;
  }
  return best <= max_range_m ? best : kInfinity;
}

double ScanWorld::CastRayBruteForce(const Eigen::Vector2d& origin, double angle_rad,
                                    double max_range_m) const {
  const Eigen::Vector2d d(std::cos(angle_rad), std::sin(angle_rad));
  double best = kInfinity;
  for (const WallSegment& s : segments_) best = std::min(best, HitDistance(s, origin, d));
  return best <= max_range_m ? best : kInfinity;
}

double ScanWorld::DistanceTo(const Eigen::Vector2d& point) const {
  double best = kInfinity;
  for (const WallSegment& s : segments_) best = std::min(best, PointSegmentDistance(point, s));
  return best;
}

}  // namespace calib

// The world builders.
namespace calib {
namespace {

constexpr double kMaxWorldSize_m = 1e4;
constexpr int kMaxClutterObjects = 20000;
constexpr double kMinWallPiece_m = 0.1;

// The path as points at most `spacing` apart.
std::vector<Eigen::Vector2d> Densify(const std::vector<Eigen::Vector2d>& path, double spacing) {
  std::vector<Eigen::Vector2d> dense{path[0]};
  for (size_t i = 1; i < path.size(); ++i) {
    const Eigen::Vector2d step = path[i] - path[i - 1];
    const int n = std::max(1, static_cast<int>(std::ceil(step.norm() / spacing)));
    for (int j = 1; j <= n; ++j) dense.push_back(path[i - 1] + step * (static_cast<double>(j) / n));
  }
  return dense;
}

// Axis `k` (0: x, 1: y) wall on the line coordinate(k) = c from `from` to `to` along the other
// axis, with the stretches in `gaps` (intervals along the line) left open.
void AddWallLine(int k, double c, double from, double to,
                 std::vector<std::pair<double, double>> gaps, std::vector<WallSegment>* walls) {
  std::sort(gaps.begin(), gaps.end());
  double pos = from;
  const auto add = [&](double a, double b) {
    if (b - a < kMinWallPiece_m) return;
    WallSegment s;
    s.a(k) = s.b(k) = c;
    s.a(1 - k) = a;
    s.b(1 - k) = b;
    walls->push_back(s);
  };
  for (const auto& [a, b] : gaps) {
    if (a > pos) add(pos, std::min(a, to));
    pos = std::max(pos, b);
    if (pos >= to) return;
  }
  add(pos, to);
}

// The stretches of the line coordinate(k) = c closer than `clearance` to a path point; `sorted`
// holds the points by coordinate k.
std::vector<std::pair<double, double>> PathGaps(int k, double c, double clearance,
                                                const std::vector<Eigen::Vector2d>& sorted) {
  std::vector<std::pair<double, double>> gaps;
  auto it = std::lower_bound(sorted.begin(), sorted.end(), c - clearance,
                             [k](const Eigen::Vector2d& p, double v) { return p(k) < v; });
  for (; it != sorted.end() && (*it)(k) <= c + clearance; ++it) {
    const double d = std::abs((*it)(k)-c);
    const double half = std::sqrt(std::max(clearance * clearance - d * d, 0.0));
    gaps.emplace_back((*it)(1 - k) - half, (*it)(1 - k) + half);
  }
  return gaps;
}

// Inner walls every room_size inside [lo, hi], one doorway per room side, opened wherever the
// path passes.
void AddRooms(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, const WorldOptions& options,
              const std::vector<Eigen::Vector2d>& points, Random* random,
              std::vector<WallSegment>* walls) {
  std::vector<double> lines[2];
  for (int k = 0; k < 2; ++k) {
    lines[k].push_back(lo(k));
    for (double c = lo(k) + options.room_size_m; c < hi(k) - 0.5 * options.room_size_m;
         c += options.room_size_m) {
      lines[k].push_back(c);
    }
    lines[k].push_back(hi(k));
  }
  for (int k = 0; k < 2; ++k) {
    std::vector<Eigen::Vector2d> sorted = points;
    std::sort(sorted.begin(), sorted.end(),
              [k](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a(k) < b(k); });
    const std::vector<double>& across = lines[1 - k];
    for (size_t i = 1; i + 1 < lines[k].size(); ++i) {
      const double c = lines[k][i];
      std::vector<std::pair<double, double>> gaps = PathGaps(k, c, options.clearance_m, sorted);
      for (size_t j = 1; j < across.size(); ++j) {
        const double room = across[j] - across[j - 1];
        const double door = std::min(options.door_width_m, 0.5 * room);
        const double at = across[j - 1] + random->Uniform(0.25 * room, 0.75 * room);
        gaps.emplace_back(at - 0.5 * door, at + 0.5 * door);
      }
      AddWallLine(k, c, lo(1 - k), hi(1 - k), std::move(gaps), walls);
    }
  }
}

// Buckets of path points, for "is any point within r of here".
class PointBuckets {
 public:
  PointBuckets(const std::vector<Eigen::Vector2d>& points, const Eigen::Vector2d& lo,
               const Eigen::Vector2d& hi, double cell)
      : lo_(lo), cell_(cell) {
    nx_ = static_cast<int>((hi.x() - lo.x()) / cell) + 1;
    ny_ = static_cast<int>((hi.y() - lo.y()) / cell) + 1;
    buckets_.resize(static_cast<size_t>(nx_) * ny_);
    for (const Eigen::Vector2d& p : points) buckets_[Index(Cell(p, 0), Cell(p, 1))].push_back(p);
  }
  bool AnyWithin(const Eigen::Vector2d& center, double radius) const {
    const int r = static_cast<int>(std::ceil(radius / cell_));
    const int cx = Cell(center, 0), cy = Cell(center, 1);
    for (int y = std::max(0, cy - r); y <= std::min(ny_ - 1, cy + r); ++y) {
      for (int x = std::max(0, cx - r); x <= std::min(nx_ - 1, cx + r); ++x) {
        for (const Eigen::Vector2d& p : buckets_[Index(x, y)]) {
          if ((p - center).squaredNorm() < radius * radius) return true;
        }
      }
    }
    return false;
  }

 private:
  int Cell(const Eigen::Vector2d& p, int k) const {
    return std::clamp(static_cast<int>((p(k) - lo_(k)) / cell_), 0, (k == 0 ? nx_ : ny_) - 1);
  }
  size_t Index(int x, int y) const { return static_cast<size_t>(y) * nx_ + x; }
  Eigen::Vector2d lo_;
  double cell_;
  int nx_ = 0, ny_ = 0;
  std::vector<std::vector<Eigen::Vector2d>> buckets_;
};

// Boxes (rotated rectangles) and pillars (octagons) clear of the path by their circumradius.
void AddClutter(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, double per_m2,
                const WorldOptions& options, const std::vector<Eigen::Vector2d>& points,
                Random* random, std::vector<WallSegment>* walls) {
  const Eigen::Vector2d size = hi - lo;
  const int count = static_cast<int>(
      std::min<double>(kMaxClutterObjects, std::round(per_m2 * size.x() * size.y())));
  const PointBuckets buckets(points, lo, hi, std::max(1.0, options.clearance_m + 0.5));
  int placed = 0;
  for (int attempt = 0; attempt < 20 * count && placed < count; ++attempt) {
    const bool pillar = random->Uniform() < 0.4;
    const Eigen::Vector2d half =
        pillar ? Eigen::Vector2d::Constant(random->Uniform(0.1, 0.3))
               : Eigen::Vector2d(random->Uniform(0.15, 0.6), random->Uniform(0.15, 0.6));
    const double radius = half.norm();
    const Eigen::Vector2d center(random->Uniform(lo.x() + radius, hi.x() - radius),
                                 random->Uniform(lo.y() + radius, hi.y() - radius));
    const double heading = random->Uniform(0.0, M_PI);
    if (buckets.AnyWithin(center, options.clearance_m + radius)) continue;
    const int sides = pillar ? 8 : 4;
    // Corners of the box (±hx, ±hy) or of the octagon, turned by the heading.
    std::vector<Eigen::Vector2d> corners;
    for (int i = 0; i < sides; ++i) {
      const double a = 2.0 * M_PI * (i + 0.5) / sides;
      const Eigen::Vector2d local =
          pillar ? Eigen::Vector2d(half.x() * std::cos(a), half.x() * std::sin(a))
                 : Eigen::Vector2d(std::cos(a) > 0 ? half.x() : -half.x(),
                                   std::sin(a) > 0 ? half.y() : -half.y());
      corners.push_back(center + Eigen::Rotation2Dd(heading) * local);
    }
    for (int i = 0; i < sides; ++i) walls->push_back({corners[i], corners[(i + 1) % sides]});
    ++placed;
  }
}

void AddBox(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, std::vector<WallSegment>* walls) {
  const Eigen::Vector2d c[4] = {lo, {hi.x(), lo.y()}, hi, {lo.x(), hi.y()}};
  for (int i = 0; i < 4; ++i) walls->push_back({c[i], c[(i + 1) % 4]});
}

Status CheckOptions(const std::vector<Eigen::Vector2d>& path, const WorldOptions& o) {
  if (path.empty()) return Status::InvalidInput("scan world: the path is empty");
  for (size_t i = 0; i < path.size(); ++i) {
    if (!path[i].allFinite()) {
      return Status::InvalidInput("scan world: path point " + std::to_string(i) + " is not finite");
    }
  }
  const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(o.clearance_m) || !positive(o.room_size_m) || !positive(o.door_width_m) ||
      !(o.margin_m >= o.clearance_m) || !std::isfinite(o.margin_m) || !(o.clutter_per_m2 >= 0.0) ||
      !(o.corridor_extension_m >= 0.0)) {
    return Status::InvalidInput(
        "scan world: options need clearance_m, room_size_m, door_width_m > 0, margin_m >= "
        "clearance_m (got margin " +
        Num(o.margin_m) + ", clearance " + Num(o.clearance_m) +
        "), clutter_per_m2 and corridor_extension_m >= 0");
  }
  return Status::Ok();
}

}  // namespace

StatusOr<ScanWorld> BuildScanWorld(const std::vector<Eigen::Vector2d>& path,
                                   const WorldOptions& options) {
  CALIB_RETURN_IF_ERROR(CheckOptions(path, options));
  Eigen::Vector2d lo = path[0], hi = path[0];
  for (const Eigen::Vector2d& p : path) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double extent =
      (hi - lo).maxCoeff() + 2.0 * options.margin_m +
      (options.kind == WorldKind::kCorridor ? 2 * options.corridor_extension_m : 0.0);
  if (!(extent <= kMaxWorldSize_m)) {
    return Status::InvalidInput("scan world: the world would span " + Num(extent) +
                                " m (path plus margins); at most " + Num(kMaxWorldSize_m) +
                                " m is supported");
  }
  // Every path point is within spacing/2 of a dense point, so keeping the dense points
  // clearance + spacing/2 away keeps the whole path clearance away.
  const double spacing = 0.1 * options.clearance_m;
  const std::vector<Eigen::Vector2d> points = Densify(path, spacing);
  WorldOptions padded = options;
  padded.clearance_m += 0.5 * spacing;
  Random random(options.seed, 1);
  std::vector<WallSegment> walls;
  if (options.kind == WorldKind::kCorridor) {
    // Walls at the clearance on both sides of the longer extent, closed far beyond the ends.
    const int along = (hi - lo).x() >= (hi - lo).y() ? 0 : 1;
    Eigen::Vector2d c_lo = lo, c_hi = hi;
    const double extension = std::max(options.corridor_extension_m, options.clearance_m);
    c_lo(along) -= extension;
    c_hi(along) += extension;
    c_lo(1 - along) -= options.clearance_m;
    c_hi(1 - along) += options.clearance_m;
    AddBox(c_lo, c_hi, &walls);
    return ScanWorld(std::move(walls));
  }
  const Eigen::Vector2d box_lo = lo.array() - options.margin_m;
  const Eigen::Vector2d box_hi = hi.array() + options.margin_m;
  AddBox(box_lo, box_hi, &walls);
  if (options.kind == WorldKind::kRooms || options.kind == WorldKind::kMixed) {
    AddRooms(box_lo, box_hi, padded, points, &random, &walls);
  }
  if (options.kind == WorldKind::kClutter || options.kind == WorldKind::kMixed) {
    const double density = options.clutter_per_m2 * (options.kind == WorldKind::kMixed ? 0.5 : 1);
    AddClutter(box_lo, box_hi, density, padded, points, &random, &walls);
  }
  return ScanWorld(std::move(walls));
}

}  // namespace calib
