#include <calib/core/odometry_drift.h>
#include <gtest/gtest.h>

#include <cmath>

namespace calib {
namespace {

TEST(OdometryDriftTest, ExactWheelsDoNotDrift) {
  const OdometryParams p{0.1, 0.1, 0.5};
  const OdometryDrift d = DriftOf(p, p);
  EXPECT_EQ(d.distance_mm_per_m, 0.0);
  EXPECT_EQ(d.heading_deg_per_m, 0.0);
  EXPECT_EQ(d.turn_deg_per_turn, 0.0);
}

// Odometry that believes the left wheel 1 % larger than it is: +5 mm per m, a right turn of
// 0.01/b rad per m, and a turn over-read by half a percent. A wheelbase believed 1 % too long
// under-reads a turn by 1/1.01.
TEST(OdometryDriftTest, KnownErrors) {
  const OdometryParams actual{0.1, 0.1, 0.5};
  OdometryDrift d = DriftOf(OdometryParams{0.101, 0.1, 0.5}, actual);
  EXPECT_NEAR(d.distance_mm_per_m, 5.0, 1e-9);
  EXPECT_NEAR(d.heading_deg_per_m, -0.01 / 0.5 * 180 / M_PI, 1e-9);
  EXPECT_NEAR(d.turn_deg_per_turn, 360 * 0.005, 1e-9);
  d = DriftOf(OdometryParams{0.1, 0.1, 0.505}, actual);
  EXPECT_NEAR(d.turn_deg_per_turn, 360 * (1 / 1.01 - 1), 1e-9);
  EXPECT_NEAR(d.distance_mm_per_m, 0.0, 1e-12);
}

// The 1σ drift is the first-order drift of a 1σ error along each parameter.
TEST(OdometryDriftTest, UncertaintyIsTheLinearisedDrift) {
  const OdometryParams c{0.099, 0.102, 0.48};
  const double h = 1e-7;
  for (int i = 0; i < 3; ++i) {
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    covariance(i, i) = h * h;
    OdometryParams actual = c;
    (i == 0 ? actual.left_radius_m : i == 1 ? actual.right_radius_m : actual.wheelbase_m) += h;
    const OdometryDrift linear = DriftFromUncertainty(c, covariance), exact = DriftOf(c, actual);
    EXPECT_NEAR(linear.distance_mm_per_m, std::abs(exact.distance_mm_per_m), 1e-9) << i;
    EXPECT_NEAR(linear.heading_deg_per_m, std::abs(exact.heading_deg_per_m), 1e-9) << i;
    EXPECT_NEAR(linear.turn_deg_per_turn, std::abs(exact.turn_deg_per_turn), 1e-9) << i;
  }
}

}  // namespace
}  // namespace calib
