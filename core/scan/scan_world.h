#ifndef CALIB_CORE_SCAN_SCAN_WORLD_H_
#define CALIB_CORE_SCAN_SCAN_WORLD_H_

#include <calib/core/status.h>

#include <Eigen/Core>
#include <cstdint>
#include <vector>

// A 2D world of wall segments for simulated range scans: ray casting through a uniform grid, and
// worlds built around a robot's path so that the robot never drives through a wall.
namespace calib {

struct WallSegment {
  Eigen::Vector2d a = Eigen::Vector2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
};

class ScanWorld {
 public:
  ScanWorld() = default;
  // Segments with non-finite ends or zero length are dropped.
  explicit ScanWorld(std::vector<WallSegment> segments);

  const std::vector<WallSegment>& segments() const { return segments_; }

  // Distance to the nearest wall along origin + t·(cos a, sin a), t ≥ 0; +inf when no wall is
  // within max_range_m. Walks the grid cells the ray crosses (Amanatides–Woo).
  double CastRay(const Eigen::Vector2d& origin, double angle_rad, double max_range_m) const;
  // The same by testing every segment (for tests).
  double CastRayBruteForce(const Eigen::Vector2d& origin, double angle_rad,
                           double max_range_m) const;
  // Distance from `point` to the nearest wall (every segment; +inf without walls).
  double DistanceTo(const Eigen::Vector2d& point) const;

 private:
  double CellHits(int cell, const Eigen::Vector2d& origin, const Eigen::Vector2d& direction,
                  double best) const;

  std::vector<WallSegment> segments_;
  Eigen::Vector2d grid_min_ = Eigen::Vector2d::Zero();
  double cell_m_ = 1.0;
  int nx_ = 0, ny_ = 0;
  std::vector<int>
      cell_start_;  // CSR: segments of cell c are cell_segments_[start[c], start[c+1]).
  std::vector<int> cell_segments_;
};

enum class WorldKind {
  kRooms,     // An outer room split into rooms by inner walls with doorways.
  kCorridor,  // A long featureless corridor along the path's longer extent.
  kClutter,   // An outer room with boxes and pillars.
  kMixed,     // Rooms and clutter.
};

struct WorldOptions {
  WorldKind kind = WorldKind::kMixed;
  double clearance_m = 0.4;  // No wall comes closer than this to the path.
  double margin_m = 2.0;     // Outer room: the path's bounding box plus this (≥ clearance).
  double room_size_m = 4.0;  // Spacing of the inner walls.
  double door_width_m = 1.0;
  double clutter_per_m2 = 0.06;        // Boxes and pillars per square metre of floor.
  double corridor_extension_m = 40.0;  // The corridor runs this far beyond the path each way.
  uint64_t seed = 1;
};

// A world around `path` (world positions the robot occupies, in order; consecutive points are
// joined by straight lines and densified, so a coarse path is enough). Fails on an empty or
// non-finite path, bad options or a path so large the world would be absurd (over 10 km).
StatusOr<ScanWorld> BuildScanWorld(const std::vector<Eigen::Vector2d>& path,
                                   const WorldOptions& options);

}  // namespace calib

#endif  // CALIB_CORE_SCAN_SCAN_WORLD_H_
