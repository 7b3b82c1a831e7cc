#include <calib/core/se2.h>
#include <calib/solvers/laser/censi_closed_form.h>
#include <gtest/gtest.h>

#include <random>

namespace calib {
namespace {

const LaserCalibration kTruth{OdometryParams{0.0206, 0.0207, 0.088}, Pose2d(-0.005, 0.006, -1.55)};

// Noise-free intervals of the given kinds: 0 straight, 1 pure rotation, 2 arc.
std::vector<LaserInterval> MakeIntervals(const std::vector<int>& kinds, int count, uint32_t seed,
                                         bool with_steps = false) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> speed(0.1, 0.6), duration(0.7, 0.9);
  std::vector<LaserInterval> intervals;
  for (int k = 0; k < count; ++k) {
    const int kind = kinds[k % kinds.size()];
    const double a = speed(rng) * (k % 4 < 2 ? 1 : -1), c = speed(rng);
    LaserInterval interval;
    interval.duration_s = duration(rng);
    interval.left_speed = kind == 1 ? -a : a;
    interval.right_speed = kind == 2 ? c : a;
    if (with_steps) {
      const double t = interval.duration_s;
      interval.steps = {{t / 2, interval.left_speed * t * 0.3, interval.right_speed * t * 0.6},
                        {t / 2, interval.left_speed * t * 0.7, interval.right_speed * t * 0.4}};
    }
    interval.sensor_motion = SensorMotionFromRobotMotion(
        kTruth.base_T_sensor,
        IntervalRobotMotion(kTruth.odometry.left_radius_m, kTruth.odometry.right_radius_m,
                            kTruth.odometry.wheelbase_m, interval));
    intervals.push_back(interval);
  }
  return intervals;
}

void ExpectRecovers(const LaserCalibration& estimate, double tol) {
  const LaserParamVector diff = estimate.ToVector() - kTruth.ToVector();
  for (int i = 0; i < kNumLaserParams; ++i) {
    EXPECT_NEAR(diff(i), 0.0, tol) << kLaserParamNames[i];
  }
}

TEST(CensiClosedFormTest, ExactOnNoiseFreeData) {
  const StatusOr<CensiClosedFormResult> result = CensiClosedForm(MakeIntervals({0, 1, 2}, 300, 1));
  ASSERT_TRUE(result.ok()) << result.message();
  ExpectRecovers(result->calibration, 1e-12);
  EXPECT_NEAR(result->j21, -0.0206 / 0.088, 1e-12);
  EXPECT_NEAR(result->j22, 0.0207 / 0.088, 1e-12);
}

TEST(CensiClosedFormTest, ExactWithNonConstantSpeeds) {
  const StatusOr<CensiClosedFormResult> result =
      CensiClosedForm(MakeIntervals({0, 1, 2}, 300, 2, /*with_steps=*/true));
  ASSERT_TRUE(result.ok()) << result.message();
  ExpectRecovers(result->calibration, 1e-12);
}

TEST(CensiClosedFormTest, ArcsAloneSuffice) {
  const StatusOr<CensiClosedFormResult> result = CensiClosedForm(MakeIntervals({2}, 200, 3));
  ASSERT_TRUE(result.ok()) << result.message();
  ExpectRecovers(result->calibration, 1e-10);
}

TEST(CensiClosedFormTest, PureRotationsAreDegenerate) {
  const StatusOr<CensiClosedFormResult> result = CensiClosedForm(MakeIntervals({1}, 200, 4));
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.message().find("pure rotations"), std::string::npos) << result.message();
  EXPECT_NE(result.message().find("b and the sensor position are not observable"),
            std::string::npos);
}

TEST(CensiClosedFormTest, StraightDrivingIsDegenerate) {
  const StatusOr<CensiClosedFormResult> result = CensiClosedForm(MakeIntervals({0}, 200, 5));
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.message().find("never turns"), std::string::npos) << result.message();
}

TEST(CensiClosedFormTest, StillRobotIsDegenerate) {
  std::vector<LaserInterval> intervals(50);
  for (LaserInterval& interval : intervals) interval.duration_s = 0.8;
  const StatusOr<CensiClosedFormResult> result = CensiClosedForm(intervals);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.message().find("barely moves"), std::string::npos) << result.message();
}

TEST(CensiClosedFormTest, SubsetMaskIsHonoured) {
  std::vector<LaserInterval> intervals = MakeIntervals({0, 1, 2}, 300, 6);
  std::vector<bool> use(intervals.size(), true);
  for (size_t k = 0; k < intervals.size(); k += 10) {  // Corrupt and mask every tenth.
    intervals[k].sensor_motion += Eigen::Vector3d(0.05, -0.05, 0.3);
    use[k] = false;
  }
  const StatusOr<CensiClosedFormResult> result = CensiClosedForm(intervals, &use);
  ASSERT_TRUE(result.ok()) << result.message();
  ExpectRecovers(result->calibration, 1e-12);
  EXPECT_EQ(result->samples_used, 270);
}

TEST(CensiClosedFormTest, TrimmingRemovesGrossOutliers) {
  std::vector<LaserInterval> intervals = MakeIntervals({0, 1, 2}, 600, 7);
  std::mt19937 rng(8);
  std::normal_distribution<double> noise(0.0, 1e-4);
  for (size_t k = 0; k < intervals.size(); ++k) {
    for (int j = 0; j < 3; ++j) intervals[k].sensor_motion(j) += noise(rng);
    if (k % 50 == 0) intervals[k].sensor_motion += Eigen::Vector3d(0.02, 0.02, 0.2);  // 2 %.
  }
  const StatusOr<CensiClosedFormResult> plain = CensiClosedForm(intervals);
  const StatusOr<TrimmedClosedFormResult> trimmed = CensiClosedFormTrimmed(intervals);
  ASSERT_TRUE(plain.ok() && trimmed.ok());
  for (size_t k = 0; k < intervals.size(); k += 50) EXPECT_FALSE(trimmed->kept[k]);
  const double plain_error = (plain->calibration.ToVector() - kTruth.ToVector()).norm();
  const double trimmed_error =
      (trimmed->estimate.calibration.ToVector() - kTruth.ToVector()).norm();
  EXPECT_LT(trimmed_error, plain_error / 5);
}

}  // namespace
}  // namespace calib
