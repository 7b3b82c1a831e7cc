#include <calib/core/diff_drive.h>
#include <calib/core/se2.h>
#include <calib/core/sin_cos.h>
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

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

// Angles around every regime of the series: zero, tiny, both sides of the cut-off, large.
std::vector<double> TestAngles() {
  const double below = std::nextafter(kSe2SmallAngle, 0.0);
  return {0.0,  1e-12, -1e-7, 3e-3, -below, below, kSe2SmallAngle, -kSe2SmallAngle, 0.011,
          -0.3, 0.7,   2.0,   -3.1, 3.1,    5.0};
}

template <typename F>
Eigen::Matrix3d CentralDifferences(const F& f, const Eigen::Vector3d& x) {
  Eigen::Matrix3d j;
  for (int k = 0; k < 3; ++k) {
    const double h = 1e-6;
    Eigen::Vector3d plus = x, minus = x;
    plus(k) += h;
    minus(k) -= h;
    j.col(k) = (f(plus) - f(minus)) / (2.0 * h);
  }
  return j;
}

using Jet3 = ceres::Jet<double, 3>;

// The value and ∂/∂x of f at x, by ceres::Jet.
template <typename F>
Eigen::Matrix3d JetJacobian(const F& f, const Eigen::Vector3d& x, Eigen::Vector3d* value) {
  Eigen::Matrix<Jet3, 3, 1> xj;
  for (int k = 0; k < 3; ++k) xj(k) = Jet3(x(k), k);
  const Eigen::Matrix<Jet3, 3, 1> y = f(xj);
  Eigen::Matrix3d j;
  for (int i = 0; i < 3; ++i) {
    (*value)(i) = y(i).a;
    j.row(i) = y(i).v.transpose();
  }
  return j;
}

TEST(Se2Test, LogOfExpIsIdentity) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> rho(-2.0, 2.0);
  for (double angle : TestAngles()) {
    for (int i = 0; i < 10; ++i) {
      const Twist2d xi(rho(rng), rho(rng), angle);
      EXPECT_LT((Log(Exp(xi)) - xi).cwiseAbs().maxCoeff(), 1e-13) << xi.transpose();
    }
  }
}

TEST(Se2Test, ExpOfLogIsIdentity) {
  std::mt19937 rng(6);
  for (int i = 0; i < 200; ++i) {
    const Pose2d p = RandomPose(&rng);
    EXPECT_LT((Exp(Log(p)) - p).cwiseAbs().maxCoeff(), 1e-13) << p.transpose();
  }
  for (double angle : TestAngles()) {
    const Pose2d p(0.3, -1.2, angle);
    EXPECT_LT((Exp(Log(p)) - p).cwiseAbs().maxCoeff(), 1e-13) << p.transpose();
  }
}

TEST(Se2Test, ExpIsTheArc) {
  // A pure forward twist is ArcDisplacement; a pure rotation is the identity translation.
  for (double angle : TestAngles()) {
    const Pose2d arc = ArcDisplacement(0.8, angle);
    EXPECT_EQ(Exp(Twist2d(0.8, 0.0, angle)), arc);
    EXPECT_EQ(Exp(Twist2d(0.0, 0.0, angle)), Pose2d(0.0, 0.0, angle));
  }
  // The lateral column is the forward one turned by 90°: Exp(0, d, θ) = R(π/2)·Exp(d, 0, θ).
  const Pose2d lateral = Exp(Twist2d(0.0, 0.8, 0.4)), forward = Exp(Twist2d(0.8, 0.0, 0.4));
  EXPECT_NEAR(lateral(0), -forward(1), 1e-15);
  EXPECT_NEAR(lateral(1), forward(0), 1e-15);
}

TEST(Se2Test, JacobiansMatchCentralDifferences) {
  const auto exp = [](const Eigen::Vector3d& x) -> Eigen::Vector3d { return Exp(Twist2d(x)); };
  const auto log = [](const Eigen::Vector3d& x) -> Eigen::Vector3d { return Log(Pose2d(x)); };
  for (double angle : TestAngles()) {
    const Twist2d xi(0.7, -0.4, angle);
    const Eigen::Matrix3d j_exp = ExpJacobian(xi);
    EXPECT_LT((j_exp - CentralDifferences(exp, xi)).cwiseAbs().maxCoeff(), 1e-8) << angle;
    const Pose2d p(0.7, -0.4, angle);
    const Eigen::Matrix3d j_log = LogJacobian(p);
    EXPECT_LT((j_log - CentralDifferences(log, p)).cwiseAbs().maxCoeff(), 1e-8) << angle;
    // The two are inverse at corresponding points.
    EXPECT_LT((LogJacobian(Exp(xi)) * j_exp - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(),
              1e-12)
        << angle;
  }
}

TEST(Se2Test, JetDerivativesMatchTheJacobians) {
  const auto exp = [](const Eigen::Matrix<Jet3, 3, 1>& x) { return Exp(Twist2<Jet3>(x)); };
  const auto log = [](const Eigen::Matrix<Jet3, 3, 1>& x) { return Log(Pose2<Jet3>(x)); };
  for (double angle : TestAngles()) {
    const Eigen::Vector3d x(0.7, -0.4, angle);
    Eigen::Vector3d value;
    const Eigen::Matrix3d j_exp = JetJacobian(exp, x, &value);
    EXPECT_LT((value - Exp(Twist2d(x))).cwiseAbs().maxCoeff(), 1e-15);  // Jet divides by 1/b.
    EXPECT_LT((j_exp - ExpJacobian(Twist2d(x))).cwiseAbs().maxCoeff(), 1e-11) << angle;
    const Eigen::Matrix3d j_log = JetJacobian(log, x, &value);
    EXPECT_LT((value - Log(Pose2d(x))).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_LT((j_log - LogJacobian(Pose2d(x))).cwiseAbs().maxCoeff(), 1e-11) << angle;
  }
}

TEST(Se2Test, SeriesAreContinuousAtTheCutOff) {
  const double below = std::nextafter(kSe2SmallAngle, 0.0);
  double s0, c0, s1, c1, ds0, dc0, ds1, dc1;
  ArcCoefficients(below, &s0, &c0);
  ArcCoefficients(kSe2SmallAngle, &s1, &c1);
  ArcCoefficientDerivatives(below, &ds0, &dc0);
  ArcCoefficientDerivatives(kSe2SmallAngle, &ds1, &dc1);
  // The closed forms round (1 − cos θ) to ~1e-16 absolute, i.e. ~1e-14 in C and ~1e-12 in C'.
  EXPECT_NEAR(s0, s1, 4 * std::numeric_limits<double>::epsilon());
  EXPECT_NEAR(c0, c1, 1e-14);
  EXPECT_NEAR(ds0, ds1, 1e-13);
  EXPECT_NEAR(dc0, dc1, 1e-11);
  // The series against the exact values in long double (S: the omitted θ⁶/5040 ≈ 2e-16).
  const long double a = kSe2SmallAngle;
  EXPECT_NEAR(s0, static_cast<double>(std::sin(a) / a), 3e-16);
  EXPECT_NEAR(c0, static_cast<double>((1.0L - std::cos(a)) / a), 1e-17);
  EXPECT_NEAR(ds0, static_cast<double>((a * std::cos(a) - std::sin(a)) / (a * a)), 1e-15);
  EXPECT_NEAR(dc0, static_cast<double>((a * std::sin(a) - 1.0L + std::cos(a)) / (a * a)), 1e-14);
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

// Within an ulp of the true values (long double's) inside ±π/4, libm's beyond; NaN stays NaN.
TEST(SinCosTest, WithinAnUlpOfTheTrueValues) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-M_PI / 4, M_PI / 4);
  const auto ulps = [](double value, long double truth) {
    const double ulp = std::ldexp(1.0, std::ilogb(static_cast<double>(truth)) - 52);
    return static_cast<double>(std::fabs(value - truth)) / ulp;
  };
  std::vector<double> angles = {0.0, -0.0, 1e-300, 1e-9, -1e-5, 0.1, M_PI / 4, -M_PI / 4};
  for (int i = 0; i < 200000; ++i) angles.push_back(angle(rng) * std::pow(10.0, -(i % 8)));
  double worst = 0.0;
  for (const double a : angles) {
    double s = 0.0, c = 0.0;
    SinCos(a, &s, &c);
    if (a != 0.0) worst = std::max(worst, ulps(s, std::sin(static_cast<long double>(a))));
    worst = std::max(worst, ulps(c, std::cos(static_cast<long double>(a))));
  }
  EXPECT_LT(worst, 1.0);
  double s = 1.0, c = 0.0;
  SinCos(-0.0, &s, &c);
  EXPECT_EQ(s, 0.0);
  EXPECT_EQ(c, 1.0);
  for (const double a : {0.8, -2.0, 3.0, 100.0, -1e6}) {
    SinCos(a, &s, &c);
    EXPECT_EQ(s, std::sin(a));
    EXPECT_EQ(c, std::cos(a));
  }
  SinCos(std::numeric_limits<double>::quiet_NaN(), &s, &c);
  EXPECT_TRUE(std::isnan(s) && std::isnan(c));
  SinCos(std::numeric_limits<double>::infinity(), &s, &c);
  EXPECT_TRUE(std::isnan(s) && std::isnan(c));
}

}  // namespace
}  // namespace calib
