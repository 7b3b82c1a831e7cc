#include <calib/core/random.h>
#include <calib/core/scan/scan_world.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace calib {
namespace {

// A 4 m × 2 m room, corners (0, 0) and (4, 2).
ScanWorld Room() {
  const Eigen::Vector2d c[4] = {{0, 0}, {4, 0}, {4, 2}, {0, 2}};
  std::vector<WallSegment> walls;
  for (int i = 0; i < 4; ++i) walls.push_back({c[i], c[(i + 1) % 4]});
  return ScanWorld(walls);
}

TEST(ScanWorldTest, SquareRoomRangesAreExact) {
  const ScanWorld room = Room();
  const Eigen::Vector2d p(1.0, 0.5);
  EXPECT_NEAR(room.CastRay(p, 0.0, 10.0), 3.0, 1e-15);
  EXPECT_NEAR(room.CastRay(p, M_PI / 2, 10.0), 1.5, 1e-15);
  EXPECT_NEAR(room.CastRay(p, M_PI, 10.0), 1.0, 1e-15);
  EXPECT_NEAR(room.CastRay(p, -M_PI / 2, 10.0), 0.5, 1e-15);
  // 45°: the top wall at y = 2 is 1.5 up, so the range is 1.5·√2 (x reaches 2.5 < 4).
  EXPECT_NEAR(room.CastRay(p, M_PI / 4, 10.0), 1.5 * std::sqrt(2.0), 1e-14);
  // Towards the corner (4, 2) exactly: hits at the shared end.
  const double corner = std::atan2(1.5, 3.0);
  EXPECT_NEAR(room.CastRay(p, corner, 10.0), std::hypot(3.0, 1.5), 1e-12);
  // Beyond range: no return.
  EXPECT_TRUE(std::isinf(room.CastRay(p, 0.0, 2.9)));
  // From outside, looking away: nothing.
  EXPECT_TRUE(std::isinf(room.CastRay(Eigen::Vector2d(-1, 1), M_PI, 100.0)));
  EXPECT_NEAR(room.CastRay(Eigen::Vector2d(-1, 1), 0.0, 100.0), 1.0, 1e-15);
}

TEST(ScanWorldTest, ClosedRoomNeverLetsARayOut) {
  const ScanWorld room = Room();
  Random random(3);
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector2d p(random.Uniform(0.01, 3.99), random.Uniform(0.01, 1.99));
    // Include the exact corner directions, where rounding could slip between two walls.
    const Eigen::Vector2d corner(i % 2 == 0 ? 4.0 : 0.0, (i / 2) % 2 == 0 ? 2.0 : 0.0);
    const double angle = i % 3 == 0 ? std::atan2(corner.y() - p.y(), corner.x() - p.x())
                                    : random.Uniform(-M_PI, M_PI);
    const double r = room.CastRay(p, angle, 100.0);
    ASSERT_TRUE(std::isfinite(r)) << p.transpose() << " angle " << angle;
    const Eigen::Vector2d hit = p + r * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    EXPECT_LT(room.DistanceTo(hit), 1e-12);
  }
}

// The grid walk returns the nearest wall of all, in a world of many segments.
TEST(ScanWorldTest, GridMatchesBruteForce) {
  std::vector<Eigen::Vector2d> path;
  for (int i = 0; i <= 200; ++i) path.emplace_back(0.1 * i, 3.0 * std::sin(0.05 * i));
  WorldOptions options;
  options.kind = WorldKind::kMixed;
  const StatusOr<ScanWorld> world = BuildScanWorld(path, options);
  ASSERT_TRUE(world.ok()) << world.status().message();
  EXPECT_GT(world->segments().size(), 50u);
  Random random(5);
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector2d p(random.Uniform(-3, 23), random.Uniform(-6, 6));
    const double angle = random.Uniform(-M_PI, M_PI);
    const double max_range = random.Uniform(0.5, 40.0);
    const double fast = world->CastRay(p, angle, max_range);
    const double slow = world->CastRayBruteForce(p, angle, max_range);
    if (std::isinf(slow)) {
      EXPECT_TRUE(std::isinf(fast));
    } else {
      EXPECT_NEAR(fast, slow, 1e-12) << i;
    }
  }
}

TEST(ScanWorldTest, EveryKindKeepsClearanceFromThePath) {
  std::vector<Eigen::Vector2d> path;
  for (int i = 0; i <= 400; ++i) {
    const double s = 0.05 * i;
    path.emplace_back(4.0 * std::cos(s) + 0.5 * s, 3.0 * std::sin(2.0 * s));
  }
  for (const WorldKind kind :
       {WorldKind::kRooms, WorldKind::kCorridor, WorldKind::kClutter, WorldKind::kMixed}) {
    WorldOptions options;
    options.kind = kind;
    options.clearance_m = 0.5;
    options.clutter_per_m2 = 0.2;
    const StatusOr<ScanWorld> world = BuildScanWorld(path, options);
    ASSERT_TRUE(world.ok()) << world.status().message();
    double closest = 1e9;
    for (size_t i = 1; i < path.size(); ++i) {
      for (int j = 0; j < 10; ++j) {
        closest =
            std::min(closest, world->DistanceTo(path[i - 1] + (path[i] - path[i - 1]) * j / 10.0));
      }
    }
    EXPECT_GE(closest, 0.5 - 1e-9) << static_cast<int>(kind);
    // The robot is enclosed: rays from the path hit walls in every direction.
    for (int a = 0; a < 360; ++a) {
      EXPECT_TRUE(std::isfinite(world->CastRay(path[0], a * M_PI / 180, 1e3)));
    }
  }
}

TEST(ScanWorldTest, RoomsHaveInnerWallsAndClutterHasObjects) {
  std::vector<Eigen::Vector2d> path{{0, 0}, {20, 0}, {20, 12}, {0, 12}};
  WorldOptions options;
  options.kind = WorldKind::kRooms;
  const size_t rooms = BuildScanWorld(path, options)->segments().size();
  EXPECT_GT(rooms, 4u + 10u);
  options.kind = WorldKind::kClutter;
  const size_t clutter = BuildScanWorld(path, options)->segments().size();
  EXPECT_GT(clutter, 4u + 4u * 10u);
  options.kind = WorldKind::kCorridor;
  EXPECT_EQ(BuildScanWorld(path, options)->segments().size(), 4u);
}

TEST(ScanWorldTest, BadInputIsAnError) {
  WorldOptions options;
  EXPECT_NE(BuildScanWorld({}, options).status().message().find("empty"), std::string::npos);
  EXPECT_NE(BuildScanWorld({{0, 0}, {NAN, 1}}, options).status().message().find("point 1"),
            std::string::npos);
  EXPECT_NE(BuildScanWorld({{0, 0}, {1e6, 0}}, options).status().message().find("span"),
            std::string::npos);
  options.margin_m = 0.1;
  EXPECT_NE(BuildScanWorld({{0, 0}}, options).status().message().find("margin"), std::string::npos);
  // Degenerate segments are dropped, an empty world sees nothing.
  const ScanWorld empty({{Eigen::Vector2d(1, 1), Eigen::Vector2d(1, 1)}});
  EXPECT_TRUE(empty.segments().empty());
  EXPECT_TRUE(std::isinf(empty.CastRay(Eigen::Vector2d::Zero(), 0.0, 10.0)));
}

}  // namespace
}  // namespace calib
