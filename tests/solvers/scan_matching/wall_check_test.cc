#include <calib/core/scan/scan_world.h>
#include <calib/solvers/scan_matching/wall_check.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace calib {
namespace {

constexpr double kDeg = M_PI / 180.0;
const OdometryParams kTruth{0.10, 0.10, 0.50};

// A closed polygon of walls.
ScanWorld Room(const std::vector<Eigen::Vector2d>& corners) {
  std::vector<WallSegment> walls;
  for (size_t i = 0; i < corners.size(); ++i) {
    walls.push_back({corners[i], corners[(i + 1) % corners.size()]});
  }
  return ScanWorld(walls);
}

struct Recording {
  std::vector<LaserScan> scans;
  std::vector<EncoderSample> wheels;
};

// A robot on a figure eight around (0, 0) (0.4 m/s, turning at ±0.4 rad/s, 60 s) with a 360-beam
// lidar at its centre (1 cm range noise), 10 scans and 100 wheel samples a second.
Recording Drive(const ScanWorld& world) {
  Recording out;
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  double x = 0.0, y = -0.5, heading = 0.0, left = 0.0, right = 0.0;
  const double dt = 0.01, v = 0.4;
  for (int k = 0; k <= 6000; ++k) {
    const double t = k * dt;
    const double w = (std::fmod(t, 31.4) < 15.7 ? 0.4 : -0.4);
    if (k % 10 == 0) {
      LaserScan scan;
      scan.stamp_s = t;
      scan.angle_min_rad = -M_PI;
      scan.angle_increment_rad = 2.0 * M_PI / 360.0;
      scan.range_max_m = 20.0;
      for (int i = 0; i < 360; ++i) {
        const double r = world.CastRay({x, y}, heading + scan.BeamAngle(i), 20.0);
        scan.ranges_m.push_back(static_cast<float>(std::isfinite(r) ? r + noise(random) : NAN));
      }
      out.scans.push_back(scan);
    }
    out.wheels.push_back({t, left, right});
    // v = r (φ_l' + φ_r')/2, ω = r (φ_r' − φ_l')/b.
    left += dt * (v - 0.5 * w * kTruth.wheelbase_m) / kTruth.left_radius_m;
    right += dt * (v + 0.5 * w * kTruth.wheelbase_m) / kTruth.right_radius_m;
    x += dt * v * std::cos(heading + 0.5 * dt * w);
    y += dt * v * std::sin(heading + 0.5 * dt * w);
    heading += dt * w;
  }
  return out;
}

// In a room whose walls meet at right angles (turned by 20°), the true wheels keep the walls'
// direction; a right wheel 1 % too large turns it by about 20° over the drive, and a wheelbase
// 5 % too short by the turns' excess, both far beyond the trend's σ.
TEST(WallCheck, TheTrueWheelsKeepTheWallsDirection) {
  std::vector<Eigen::Vector2d> corners = {{-4, -3}, {4, -3}, {4, 3}, {-4, 3}};
  for (Eigen::Vector2d& c : corners) c = Eigen::Rotation2Dd(20.0 * kDeg) * c;
  const Recording r = Drive(Room(corners));
  const OdometryParams right_large{0.10, 0.101, 0.50};
  const WallCheck truth = CheckAgainstWalls(r.scans, false, r.wheels, kTruth, right_large, 0.0);
  EXPECT_TRUE(truth.right_angled);
  EXPECT_EQ(truth.scans_with_walls, truth.scans);
  EXPECT_LT(std::abs(truth.calibrated.drift_rad), 1.0 * kDeg);
  EXPECT_LT(truth.calibrated.scatter_rad, 1.0 * kDeg);
  ASSERT_TRUE(truth.nominal.has_value());
  EXPECT_GT(std::abs(truth.nominal->drift_rad), 10.0 * kDeg);
  EXPECT_GT(std::abs(truth.nominal->drift_rad), 5.0 * truth.nominal->drift_stddev_rad);

  // The drift's σ through the wheels' covariance: a σ of 1 mm on r_r alone moves the drift as
  // r_r + 1 mm does.
  const Eigen::Matrix3d r_r_only = Eigen::Vector3d(0.0, 1e-6, 0.0).asDiagonal();
  const WallCheck with_sigma =
      CheckAgainstWalls(r.scans, false, r.wheels, kTruth, {}, 0.0, r_r_only);
  EXPECT_NEAR(with_sigma.calibrated.calibration_stddev_rad,
              std::abs(truth.nominal->drift_rad - truth.calibrated.drift_rad),
              0.05 * std::abs(truth.nominal->drift_rad));
  EXPECT_EQ(truth.calibrated.calibration_stddev_rad, 0.0);  // No covariance given.

  const OdometryParams short_base{0.10, 0.10, 0.475};
  const WallCheck turns = CheckAgainstWalls(r.scans, false, r.wheels, short_base, {}, 0.0);
  EXPECT_GT(turns.calibrated.scatter_rad, 3.0 * truth.calibrated.scatter_rad);
  EXPECT_FALSE(turns.nominal.has_value());

  // An upside-down lidar's scans, as recorded, are the mirror image.
  Recording mirrored = r;
  for (LaserScan& scan : mirrored.scans) std::reverse(scan.ranges_m.begin(), scan.ranges_m.end());
  const WallCheck flipped = CheckAgainstWalls(mirrored.scans, true, r.wheels, kTruth, {}, 0.0);
  EXPECT_TRUE(flipped.right_angled);
  EXPECT_LT(std::abs(flipped.calibrated.drift_rad), 1.0 * kDeg);
}

// A hexagonal room has no right angles: the check says so instead of judging the heading.
TEST(WallCheck, WallsThatDoNotMeetAtRightAnglesAreNoCheck) {
  std::vector<Eigen::Vector2d> corners;
  for (int k = 0; k < 6; ++k)
    corners.emplace_back(5 * std::cos(k * M_PI / 3), 5 * std::sin(k * M_PI / 3));
  const Recording r = Drive(Room(corners));
  const WallCheck check = CheckAgainstWalls(r.scans, false, r.wheels, kTruth, {}, 0.0);
  EXPECT_FALSE(check.right_angled);
  // Too few scans or no wheels: nothing computed.
  const WallCheck none = CheckAgainstWalls({}, false, r.wheels, kTruth, {}, 0.0);
  EXPECT_FALSE(none.right_angled);
  EXPECT_EQ(none.duration_s, 0.0);
}

}  // namespace
}  // namespace calib
