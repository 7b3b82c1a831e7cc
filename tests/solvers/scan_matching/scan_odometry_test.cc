#include <calib/solvers/scan_matching/scan_odometry.h>
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cstdio>
#include <random>

#include "tests/solvers/scan_matching/test_scans.h"

namespace calib {
namespace {

using test_scans::CastScan;
using test_scans::ScanSpec;

Eigen::Vector3d PoseDifference(const Pose2d& estimate, const Pose2d& truth) {
  Eigen::Vector3d d = estimate - truth;
  d(2) = WrapAngle(d(2));
  return d;
}

double Mahalanobis2(const Eigen::Vector3d& error, const Eigen::Matrix3d& covariance) {
  return error.dot(covariance.ldlt().solve(error));
}

TEST(ScanOdometryTest, RobotAtRestDoesNotDrift) {
  const auto room = test_scans::RoomWithBoxes();
  const Pose2d pose(0.4, -0.3, 0.2);
  const std::vector<LaserScan> scans(100, CastScan(room, pose, ScanSpec{}));
  std::mt19937 rng(1);
  std::normal_distribution<double> odometry_noise(0.0, 0.01);
  std::vector<Pose2d> guesses;
  for (int i = 0; i < 99; ++i) {
    guesses.emplace_back(odometry_noise(rng), odometry_noise(rng), odometry_noise(rng));
  }
  ScanOdometryOptions options;
  options.world_T_first_sensor = pose;
  const StatusOr<ScanOdometryResult> result = RunScanOdometry(scans, guesses, options);
  ASSERT_TRUE(result.ok()) << result.message();
  ASSERT_EQ(result->size(), 100);
  EXPECT_TRUE(result->failed.empty());
  for (int i = 1; i < 100; ++i) {
    EXPECT_EQ(result->keyframe_of[i], 0);
    EXPECT_TRUE(result->PairIsValid(i - 1));
  }
  // Not exactly zero: a point's line runs through its neighbours, whose float ranges are rounded
  // (~0.2 µm at 3 m); one match's error, not a drift.
  EXPECT_LT(PoseDifference(result->poses.back().world_T_sensor, pose).norm(), 1e-8);
}

// With noisy scans at rest every scan is matched to the same keyframe: the errors stay those of
// one match (they share the keyframe's noise) instead of growing like a random walk, which over
// 99 frame-to-frame matches would reach ~10 times one match's σ.
TEST(ScanOdometryTest, NoisyScansAtRestStayWithinOneMatchError) {
  const auto room = test_scans::RoomWithBoxes();
  ScanSpec spec;
  spec.range_sigma_m = 0.01;
  std::mt19937 rng(2);
  std::vector<LaserScan> scans;
  for (int i = 0; i < 100; ++i) scans.push_back(CastScan(room, Pose2d::Zero(), spec, &rng));
  const StatusOr<ScanOdometryResult> result =
      RunScanOdometry(scans, std::vector<Pose2d>(99, Pose2d::Zero()));
  ASSERT_TRUE(result.ok()) << result.message();
  EXPECT_TRUE(result->failed.empty());
  double worst = 0.0;
  for (int i = 1; i < 100; ++i) {
    EXPECT_EQ(result->keyframe_of[i], 0);
    const Eigen::Matrix3d& cov = result->covariances[i];
    for (int k = 0; k < 3; ++k) {
      worst = std::max(worst, std::abs(result->poses[i].world_T_sensor(k)) / std::sqrt(cov(k, k)));
    }
  }
  // 297 errors of 3 dof, correlated through the keyframe: the worst stays within ~3σ (the bound
  // was 8σ while the lines ran through the nearest points, whose noise leans towards the point).
  std::printf("worst error at rest: %.2f sigma of one match\n", worst);
  EXPECT_LT(worst, 4.0);
  // Frame to frame (every scan a keyframe) the same data walks away.
  ScanOdometryOptions frame_to_frame;
  frame_to_frame.keyframe_distance_m = 0.0;
  frame_to_frame.keyframe_angle_rad = 0.0;
  const StatusOr<ScanOdometryResult> walk =
      RunScanOdometry(scans, std::vector<Pose2d>(99, Pose2d::Zero()), frame_to_frame);
  ASSERT_TRUE(walk.ok()) << walk.message();
  const double walked_m = walk->poses.back().world_T_sensor.head<2>().norm();
  const double kept_m = result->poses.back().world_T_sensor.head<2>().norm();
  std::printf("after 100 scans at rest: %.2e m with keyframes, %.2e m frame to frame\n", kept_m,
              walked_m);
  EXPECT_LT(3.0 * kept_m, walked_m);
}

// A loop of 200 noisy scans with noisy odometry guesses: the poses agree with the truth within
// the covariances propagated through the keyframes.
TEST(ScanOdometryTest, ChainOfNoisyScansIsConsistentWithItsCovariances) {
  const auto room = test_scans::RoomWithBoxes();
  ScanSpec spec;
  spec.range_sigma_m = 0.01;
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  const int n = 200;
  std::vector<Pose2d> truth;
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * M_PI * i / n;
    truth.emplace_back(1.2 * std::cos(a), 0.2 + 1.2 * std::sin(a), WrapAngle(a + 0.5 * M_PI));
  }
  std::vector<LaserScan> scans;
  std::vector<Pose2d> guesses;
  for (int i = 0; i < n; ++i) {
    scans.push_back(CastScan(room, truth[i], spec, &rng));
    scans.back().stamp_s = 0.1 * i;
    if (i > 0) {
      guesses.push_back(Between(truth[i - 1], truth[i]) +
                        Pose2d(0.005 * noise(rng), 0.005 * noise(rng), 0.005 * noise(rng)));
    }
  }
  ScanOdometryOptions options;
  options.world_T_first_sensor = truth[0];
  const StatusOr<ScanOdometryResult> result = RunScanOdometry(scans, guesses, options);
  ASSERT_TRUE(result.ok()) << result.message();
  EXPECT_TRUE(result->failed.empty());
  int keyframes = 0;
  int inside = 0;
  double worst = 0.0;
  for (int i = 1; i < n; ++i) {
    keyframes += result->keyframe_of[i] != result->keyframe_of[i - 1];
    const double d2 = Mahalanobis2(PoseDifference(result->poses[i].world_T_sensor, truth[i]),
                                   result->covariances[i]);
    inside += d2 < 14.16;  // χ²₃ at 99.7 %.
    worst = std::max(worst, d2);
    EXPECT_DOUBLE_EQ(result->poses[i].t_s, 0.1 * i);
  }
  const Eigen::Vector3d final_error =
      PoseDifference(result->poses.back().world_T_sensor, truth.back());
  std::printf(
      "keyframes %d, final error (%.2e, %.2e, %.2e), final sigma (%.2e, %.2e, %.2e), "
      "%d of %d within 3 sigma, worst Mahalanobis^2 %.1f\n",
      keyframes, final_error(0), final_error(1), final_error(2),
      std::sqrt(result->covariances.back()(0, 0)), std::sqrt(result->covariances.back()(1, 1)),
      std::sqrt(result->covariances.back()(2, 2)), inside, n - 1, worst);
  EXPECT_GE(inside, (n - 1) * 9 / 10);
  EXPECT_LT(Mahalanobis2(final_error, result->covariances.back()), 16.0);
}

TEST(ScanOdometryTest, FailedMatchesBecomeGaps) {
  const auto room = test_scans::RoomWithBoxes();
  std::vector<LaserScan> scans;
  std::vector<Pose2d> guesses;
  const Pose2d step(0.02, 0.0, 0.01);
  Pose2d pose = Pose2d::Zero();
  for (int i = 0; i < 10; ++i) {
    scans.push_back(CastScan(room, pose, ScanSpec{}));
    if (i > 0) guesses.push_back(step);
    pose = Compose(pose, step);
  }
  for (size_t b = 10; b < scans[5].ranges_m.size(); ++b) scans[5].ranges_m[b] = INFINITY;
  scans[7].angle_increment_rad = NAN;  // Malformed: a gap too, not an error of the run.
  const StatusOr<ScanOdometryResult> result = RunScanOdometry(scans, guesses);
  ASSERT_TRUE(result.ok()) << result.message();
  EXPECT_EQ(result->failed, (std::vector<int>{5, 7}));
  EXPECT_EQ(result->chain[5], -1);
  EXPECT_EQ(result->matches[5].quality, ScanMatchQuality::kTooFewCorrespondences);
  EXPECT_FALSE(result->matches[7].reason.empty());
  for (int i = 0; i + 1 < 10; ++i) {
    const bool expected = i != 4 && i != 5 && i != 6 && i != 7;
    EXPECT_EQ(result->PairIsValid(i), expected) << i;
  }
  // The scans after a gap are still matched against the keyframe, exactly.
  Pose2d truth = Pose2d::Zero();
  for (int i = 0; i < 9; ++i) truth = Compose(truth, step);
  EXPECT_LT(PoseDifference(result->poses[9].world_T_sensor, truth).norm(), 1e-6);
}

TEST(ScanOdometryTest, RestartsAChainAfterRepeatedFailures) {
  const auto room = test_scans::RoomWithBoxes();
  const std::vector<LaserScan> scans(8, CastScan(room, Pose2d::Zero(), ScanSpec{}));
  // Odometry claims a quarter turn before scan 2: scans 2, 3, 4 fail against keyframe 0, and
  // scan 4 starts a new chain that scans 5–7 extend.
  std::vector<Pose2d> guesses(7, Pose2d::Zero());
  guesses[1] = Pose2d(0.0, 0.0, 1.5);
  ScanOdometryOptions options;
  options.max_consecutive_failures = 3;
  const StatusOr<ScanOdometryResult> result = RunScanOdometry(scans, guesses, options);
  ASSERT_TRUE(result.ok()) << result.message();
  EXPECT_EQ(result->failed, (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(result->chain[2], -1);
  EXPECT_EQ(result->chain[4], 1);
  EXPECT_EQ(result->chain[7], 1);
  EXPECT_TRUE(result->PairIsValid(0));
  EXPECT_FALSE(result->PairIsValid(1));
  EXPECT_FALSE(result->PairIsValid(3));
  EXPECT_TRUE(result->PairIsValid(4));
  EXPECT_TRUE(result->PairIsValid(6));
}

TEST(ScanOdometryTest, ScansWithTooFewReturnsDoNotStartAChain) {
  const auto room = test_scans::RoomWithBoxes();
  std::vector<LaserScan> scans(8, CastScan(room, Pose2d::Zero(), ScanSpec{}));
  for (int i = 2; i <= 4; ++i) {
    for (size_t b = 10; b < scans[i].ranges_m.size(); ++b) scans[i].ranges_m[b] = NAN;
  }
  const StatusOr<ScanOdometryResult> result =
      RunScanOdometry(scans, std::vector<Pose2d>(7, Pose2d::Zero()));
  ASSERT_TRUE(result.ok()) << result.message();
  EXPECT_EQ(result->failed, (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(result->chain[5], result->chain[0]);
  EXPECT_FALSE(result->PairIsValid(4));
  EXPECT_TRUE(result->PairIsValid(5));
}

TEST(ScanOdometryTest, RejectsMismatchedOrNonFiniteGuesses) {
  const auto room = test_scans::RoomWithBoxes();
  const std::vector<LaserScan> scans(3, CastScan(room, Pose2d::Zero(), ScanSpec{}));
  EXPECT_EQ(RunScanOdometry(scans, std::vector<Pose2d>(3, Pose2d::Zero())).code(),
            StatusCode::kInvalidInput);
  EXPECT_EQ(RunScanOdometry(scans, {Pose2d::Zero(), Pose2d(NAN, 0, 0)}).code(),
            StatusCode::kInvalidInput);
  const StatusOr<ScanOdometryResult> empty = RunScanOdometry({}, {});
  ASSERT_TRUE(empty.ok());
  EXPECT_EQ(empty->size(), 0);
}

}  // namespace
}  // namespace calib
