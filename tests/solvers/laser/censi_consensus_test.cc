#include <calib/core/se2.h>
#include <calib/solvers/laser/censi_closed_form.h>
#include <calib/solvers/laser/censi_consensus.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace calib {
namespace {

const LaserCalibration kTruth{OdometryParams{0.0206, 0.0207, 0.088}, Pose2d(-0.005, 0.006, -1.55)};

// Noise-free intervals cycling through straight runs, turns on the spot and arcs.
std::vector<LaserInterval> MakeIntervals(int count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> speed(0.1, 0.6), duration(0.7, 0.9);
  std::vector<LaserInterval> intervals;
  for (int k = 0; k < count; ++k) {
    const int kind = k % 3;
    const double a = speed(rng) * (k % 4 < 2 ? 1 : -1), c = speed(rng);
    LaserInterval interval;
    interval.duration_s = duration(rng);
    interval.left_speed = kind == 1 ? -a : a;
    interval.right_speed = kind == 2 ? c : a;
    interval.sensor_motion = SensorMotionFromRobotMotion(
        kTruth.base_T_sensor,
        IntervalRobotMotion(kTruth.odometry.left_radius_m, kTruth.odometry.right_radius_m,
                            kTruth.odometry.wheelbase_m, interval));
    interval.record = k + 1;
    intervals.push_back(interval);
  }
  return intervals;
}

double MaxError(const LaserCalibration& estimate) {
  return (estimate.ToVector() - kTruth.ToVector()).cwiseAbs().maxCoeff();
}

TEST(CensiConsensusTest, NoiseFreeLogKeepsEveryInterval) {
  const std::vector<LaserInterval> intervals = MakeIntervals(300, 1);
  const ConsensusScreen screen = ScreenGrossIntervals(intervals);
  EXPECT_EQ(screen.outliers(), 0);
  EXPECT_EQ(screen.first_outlier, -1);
  const StatusOr<CensiClosedFormResult> screened = CensiClosedFormScreened(intervals);
  ASSERT_TRUE(screened.ok()) << screened.message();
  EXPECT_LT(MaxError(screened->calibration), 1e-9);
}

// The glitches, each in an otherwise exact 1000-interval log: the plain closed form is
// dragged far off (or fails); the screened one leaves out exactly the glitch and is exact.
struct Glitch {
  const char* name;
  void (*apply)(LaserInterval*);
};

class GlitchTest : public ::testing::TestWithParam<Glitch> {};

TEST_P(GlitchTest, OneGlitchCostsOneInterval) {
  std::vector<LaserInterval> intervals = MakeIntervals(999, 2);
  constexpr size_t kAt = 500;
  GetParam().apply(&intervals[kAt]);
  const StatusOr<CensiClosedFormResult> plain = CensiClosedForm(intervals);
  EXPECT_TRUE(!plain.ok() || MaxError(plain->calibration) > 1e-4) << "the glitch did not matter";
  ConsensusScreen screen;
  const StatusOr<CensiClosedFormResult> screened = CensiClosedFormScreened(intervals, &screen);
  ASSERT_TRUE(screened.ok()) << screened.message();
  EXPECT_EQ(screen.outliers(), 1);
  EXPECT_EQ(screen.first_outlier, static_cast<int>(kAt));
  EXPECT_LT(MaxError(screened->calibration), 1e-9);
  // The seed of the refinement (the trimmed closed form) starts from the screen too.
  const StatusOr<TrimmedClosedFormResult> trimmed = CensiClosedFormTrimmed(intervals);
  ASSERT_TRUE(trimmed.ok()) << trimmed.message();
  EXPECT_EQ(trimmed->gross, 1);
  EXPECT_LT(MaxError(trimmed->estimate.calibration), 1e-9);
}

INSTANTIATE_TEST_SUITE_P(
    Glitches, GlitchTest,
    ::testing::Values(Glitch{"phi_l_1000", [](LaserInterval* i) { i->left_speed = 1000.0; }},
                      Glitch{"T_1e4", [](LaserInterval* i) { i->duration_s = 1e4; }},
                      Glitch{"theta_plus_2pi",
                             [](LaserInterval* i) { i->sensor_motion(2) += 2.0 * M_PI; }},
                      Glitch{"sm_x_100m", [](LaserInterval* i) { i->sensor_motion(0) = 100.0; }}),
    [](const ::testing::TestParamInfo<Glitch>& info) { return std::string(info.param.name); });

// A rotation near π written as −π is a 2π error in the rotation stage: one interval.
TEST(CensiConsensusTest, PiWrittenAsMinusPi) {
  std::vector<LaserInterval> intervals = MakeIntervals(300, 3);
  LaserInterval& turn = intervals[150];
  turn.left_speed = -0.5;
  turn.right_speed = 0.5;
  turn.duration_s = M_PI * kTruth.odometry.wheelbase_m / (0.5 * 0.5 * (0.0206 + 0.0207));
  turn.sensor_motion = SensorMotionFromRobotMotion(
      kTruth.base_T_sensor,
      IntervalRobotMotion(kTruth.odometry.left_radius_m, kTruth.odometry.right_radius_m,
                          kTruth.odometry.wheelbase_m, turn));
  turn.sensor_motion(2) = -M_PI;
  ConsensusScreen screen;
  const StatusOr<CensiClosedFormResult> screened = CensiClosedFormScreened(intervals, &screen);
  ASSERT_TRUE(screened.ok()) << screened.message();
  EXPECT_EQ(screen.outliers(), 1);
  EXPECT_LT(MaxError(screened->calibration), 1e-6);
}

// Up to just under half the intervals gross, the consensus still finds the robot.
TEST(CensiConsensusTest, SurvivesFortyPercentGross) {
  std::vector<LaserInterval> intervals = MakeIntervals(600, 4);
  std::mt19937 rng(5);
  std::normal_distribution<double> gross(0.0, 0.3);
  int corrupted = 0;
  for (size_t k = 0; k < intervals.size(); k += 5) {
    for (size_t j = k; j < k + 2 && j < intervals.size(); ++j, ++corrupted) {
      intervals[j].sensor_motion += Pose2d(gross(rng), gross(rng), gross(rng));
    }
  }
  ConsensusScreen screen;
  const StatusOr<CensiClosedFormResult> screened = CensiClosedFormScreened(intervals, &screen);
  ASSERT_TRUE(screened.ok()) << screened.message();
  EXPECT_GE(screen.outliers(), corrupted * 9 / 10);
  EXPECT_LT(MaxError(screened->calibration), 1e-6);
}

// The screen keeps its closed form for the closed forms that start from it: the same as computing
// it on the kept intervals; with other options, or without one, it is computed; the trimmed closed
// form from the screen is the one from a fresh screen.
TEST(CensiConsensusTest, TheScreensClosedFormIsReused) {
  std::vector<LaserInterval> intervals = MakeIntervals(600, 8);
  intervals[17].sensor_motion(2) += 1.0;
  ConsensusScreen screen;
  const StatusOr<CensiClosedFormResult> screened = CensiClosedFormScreened(intervals, &screen);
  ASSERT_TRUE(screened.ok() && screen.closed_form.has_value());
  const StatusOr<CensiClosedFormResult> computed = CensiClosedForm(intervals, &screen.kept);
  const StatusOr<CensiClosedFormResult> reused = ClosedFormOnKept(intervals, screen);
  ASSERT_TRUE(computed.ok() && reused.ok());
  EXPECT_EQ(reused->calibration.ToVector(), computed->calibration.ToVector());
  EXPECT_EQ(reused->samples_used, computed->samples_used);

  ConsensusScreen marked = screen;  // A closed form it would not compute: not reused.
  marked.closed_form->calibration.odometry.wheelbase_m = 1.0;
  CensiClosedFormOptions strict;
  strict.max_condition_number = 1e6;
  EXPECT_EQ(ClosedFormOnKept(intervals, marked, strict)->calibration.ToVector(),
            CensiClosedForm(intervals, &screen.kept, strict)->calibration.ToVector());
  marked.closed_form.reset();
  EXPECT_EQ(ClosedFormOnKept(intervals, marked)->calibration.ToVector(),
            computed->calibration.ToVector());

  const StatusOr<TrimmedClosedFormResult> from_screen =
      CensiClosedFormTrimmed(intervals, {}, &screen);
  const StatusOr<TrimmedClosedFormResult> fresh = CensiClosedFormTrimmed(intervals);
  ASSERT_TRUE(from_screen.ok() && fresh.ok());
  EXPECT_EQ(from_screen->estimate.calibration.ToVector(), fresh->estimate.calibration.ToVector());
  EXPECT_EQ(from_screen->kept, fresh->kept);
  EXPECT_EQ(from_screen->gross, 1);
}

// Too few moving intervals for a consensus: nothing is screened, never a failure.
TEST(CensiConsensusTest, TinyLogKeepsEverything) {
  const std::vector<LaserInterval> intervals = MakeIntervals(3, 6);
  const ConsensusScreen screen = ScreenGrossIntervals(intervals);
  EXPECT_EQ(screen.outliers(), 0);
  EXPECT_EQ(screen.kept.size(), 3u);
}

}  // namespace
}  // namespace calib
