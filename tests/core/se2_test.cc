#include <calib/core/se2.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <calib/core/diff_drive.h>

namespace calib {
namespace {

Pose2d RandomPose(std::mt19937* rng) {
  std::uniform_real_distribution<double> xy(-2.0, 2.0);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  return Pose2d(xy(*rng), xy(*rng), angle(*rng));
}

void ExpectPoseNear(const Pose2d& a, const Pose2d& b, double tol) {
  EXPECT_NEAR(a(0), b(0), tol);
  EXPECT_NEAR(a(1), b(1), tol);
  EXPECT_NEAR(WrapAngle(a(2) - b(2)), 0.0, tol);
}

TEST(Se2Test, ComposeWithInverseIsIdentity) {
  std::mt19937 rng(1);
  for (int i = 0; i < 100; ++i) {
    const Pose2d a = RandomPose(&rng);
    ExpectPoseNear(Compose(a, Inverse(a)), Pose2d::Zero(), 1e-12);
    ExpectPoseNear(Compose(Inverse(a), a), Pose2d::Zero(), 1e-12);
  }
}

TEST(Se2Test, ComposeIsAssociative) {
  std::mt19937 rng(2);
  for (int i = 0; i < 100; ++i) {
    const Pose2d a = RandomPose(&rng), b = RandomPose(&rng), c = RandomPose(&rng);
    ExpectPoseNear(Compose(Compose(a, b), c), Compose(a, Compose(b, c)), 1e-12);
  }
}

TEST(Se2Test, BetweenIsInverseThenCompose) {
  std::mt19937 rng(3);
  for (int i = 0; i < 100; ++i) {
    const Pose2d a = RandomPose(&rng), c = RandomPose(&rng);
    ExpectPoseNear(Between(a, c), Compose(Inverse(a), c), 1e-12);
    ExpectPoseNear(Compose(a, Between(a, c)), c, 1e-12);
  }
}

TEST(Se2Test, ComposeMatchesCensiDefinition) {
  // Censi 2008, symbols table: a ⊕ b = (ax + bx cos aθ − by sin aθ, ay + bx sin aθ + by cos aθ,
  // aθ + bθ).
  const Pose2d a(1.0, 2.0, 0.5), b(-0.3, 0.7, 1.1);
  const Pose2d expected(1.0 - 0.3 * std::cos(0.5) - 0.7 * std::sin(0.5),
                        2.0 - 0.3 * std::sin(0.5) + 0.7 * std::cos(0.5), 1.6);
  ExpectPoseNear(Compose(a, b), expected, 1e-15);
}

TEST(Se2Test, WrapAngleRange) {
  EXPECT_DOUBLE_EQ(WrapAngle(M_PI), M_PI);
  EXPECT_DOUBLE_EQ(WrapAngle(-M_PI), M_PI);
  EXPECT_NEAR(WrapAngle(3 * M_PI + 0.1), -M_PI + 0.1, 1e-12);
  EXPECT_NEAR(WrapAngle(-0.2), -0.2, 1e-15);
}

TEST(Se2Test, SensorMotionSatisfiesCensiConstraint) {
  // ℓ ⊕ s = o ⊕ ℓ (Censi eq. 9).
  std::mt19937 rng(4);
  for (int i = 0; i < 50; ++i) {
    const Pose2d l = RandomPose(&rng), o = RandomPose(&rng);
    ExpectPoseNear(Compose(l, SensorMotionFromRobotMotion(l, o)), Compose(o, l), 1e-12);
  }
}

// The arc must match a fine numerical integration of the unicycle (Censi eq. 1).
Pose2d IntegrateUnicycle(double v, double w, double duration, int steps) {
  Pose2d q = Pose2d::Zero();
  const double h = duration / steps;
  auto f = [&](const Pose2d& p) { return Pose2d(v * std::cos(p(2)), v * std::sin(p(2)), w); };
  for (int i = 0; i < steps; ++i) {  // RK4.
    const Pose2d k1 = f(q), k2 = f(q + h / 2 * k1), k3 = f(q + h / 2 * k2), k4 = f(q + h * k3);
    q += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
  }
  return q;
}

TEST(DiffDriveTest, ArcMatchesNumericalIntegration) {
  for (double w : {-2.0, -0.3, -1e-3, -1e-9, 0.0, 1e-7, 5e-3, 0.011, 0.7, 3.0}) {
    const double v = 0.3, duration = 0.9;
    ExpectPoseNear(ArcDisplacement(v * duration, w * duration),
                   IntegrateUnicycle(v, w, duration, 2000), 1e-12);
  }
}

TEST(DiffDriveTest, SeriesIsContinuousAtThreshold) {
  const double below = std::nextafter(1e-2, 0.0);
  const Pose2d a = ArcDisplacement(1.0, below), b = ArcDisplacement(1.0, 1e-2);
  EXPECT_NEAR(a(0), b(0), 1e-14);
  EXPECT_NEAR(a(1), b(1), 1e-14);
}

TEST(DiffDriveTest, WheelJacobianMatchesContractSpeeds) {
  const double rl = 0.02, rr = 0.021, b = 0.09, pl = 0.4, pr = -0.3;
  const Eigen::Vector2d vw = WheelJacobian(rl, rr, b) * Eigen::Vector2d(pl, pr);
  EXPECT_NEAR(vw(0), (rl * pl + rr * pr) / 2, 1e-15);
  EXPECT_NEAR(vw(1), (rr * pr - rl * pl) / b, 1e-15);
}

TEST(DiffDriveTest, StepsOfEqualSpeedMatchOneStep) {
  const double rl = 0.02, rr = 0.021, b = 0.09;
  std::vector<WheelStep> steps(7, WheelStep{0.1, 0.05, 0.09});
  ExpectPoseNear(IntegrateWheelSteps(rl, rr, b, steps),
                 WheelStepDisplacement(rl, rr, b, 0.35, 0.63), 1e-13);
}

}  // namespace
}  // namespace calib
