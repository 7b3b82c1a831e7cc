#include <calib/core/laser/laser_plausibility.h>
#include <gtest/gtest.h>

#include <cmath>

namespace calib {
namespace {

// n turning-and-driving intervals of about 0.8 s at a few rad/s, sm of centimetres.
LaserLog MakeLog(int n) {
  LaserLog log;
  log.source = "log.csv";
  for (int k = 0; k < n; ++k) {
    LaserInterval interval;
    interval.duration_s = 0.8 + 0.01 * (k % 7);
    interval.left_speed = 1.0 + 0.1 * (k % 5);
    interval.right_speed = 2.0 - 0.1 * (k % 3);
    interval.sensor_motion = Pose2d(0.02 + 0.001 * (k % 4), 0.001, 0.03 * ((k % 2) ? 1 : -1));
    interval.record = k + 1;
    interval.line = k + 2;
    log.intervals.push_back(interval);
  }
  return log;
}

TEST(LaserPlausibilityTest, PlausibleLogIsUntouched) {
  LaserLog log = MakeLog(200);
  DropImplausibleIntervals(&log);
  EXPECT_EQ(log.intervals.size(), 200u);
  EXPECT_TRUE(log.warnings.empty());
}

struct Case {
  const char* name;
  void (*apply)(LaserInterval*);
  const char* says;
};

class ImplausibleTest : public ::testing::TestWithParam<Case> {};

TEST_P(ImplausibleTest, DroppedWithTheRecordNamed) {
  LaserLog log = MakeLog(300);
  GetParam().apply(&log.intervals[100]);
  DropImplausibleIntervals(&log);
  ASSERT_EQ(log.intervals.size(), 299u);
  EXPECT_TRUE(log.intervals[100].gap_before);  // The next one follows a hole.
  ASSERT_EQ(log.warnings.size(), 1u);
  EXPECT_NE(log.warnings[0].find("record 101 (line 102)"), std::string::npos) << log.warnings[0];
  EXPECT_NE(log.warnings[0].find(GetParam().says), std::string::npos) << log.warnings[0];
}

INSTANTIATE_TEST_SUITE_P(
    Glitches, ImplausibleTest,
    ::testing::Values(
        Case{"absurd", [](LaserInterval* i) { i->sensor_motion(2) = 5e307; }, "no unit explains"},
        Case{"full_turn", [](LaserInterval* i) { i->sensor_motion(2) = 100.0; }, "full turn"},
        Case{"wheel", [](LaserInterval* i) { i->left_speed = 1e4; }, "left wheel's rotation"},
        Case{"duration", [](LaserInterval* i) { i->duration_s = 1e4; }, "T = "},
        Case{"displacement", [](LaserInterval* i) { i->sensor_motion(0) = 100.0; },
             "displacement"}),
    [](const ::testing::TestParamInfo<Case>& info) { return std::string(info.param.name); });

// θ in degrees turns by more than 2π in many intervals: the log's unit, not a glitch. Kept, for
// the input checks to name.
TEST(LaserPlausibilityTest, ManyOfAKindAreKept) {
  LaserLog log = MakeLog(300);
  for (LaserInterval& interval : log.intervals) interval.sensor_motion(2) *= 180.0 / M_PI * 5;
  DropImplausibleIntervals(&log);
  EXPECT_EQ(log.intervals.size(), 300u);
}

// A mostly still robot: the scale is that of its few moving intervals, which are kept.
TEST(LaserPlausibilityTest, MostlyStillLogKeepsItsMotion) {
  LaserLog log = MakeLog(300);
  for (size_t k = 0; k < 280; ++k) {
    log.intervals[k].left_speed = log.intervals[k].right_speed = 0.0;
    log.intervals[k].sensor_motion = Pose2d::Zero();
  }
  DropImplausibleIntervals(&log);
  EXPECT_EQ(log.intervals.size(), 300u);
}

}  // namespace
}  // namespace calib
