// The bearing route's input checks: a log whose wheels are read wrongly (a sign, swapped columns,
// degrees, ticks) is refused with what to fix, where the bearing model would fit it as well as
// the right one and return a confident wrong number.
#include <calib/core/bearing/bearing_simulator.h>
#include <calib/solvers/bearing/bearing_input_checks.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace calib {
namespace {

BearingLog Simulated() {
  BearingSimOptions o;  // Martinelli's §8.1 circles, the landmark 1 m away at run 1's start.
  o.bearing_noise_rad = M_PI / 180.0;
  o.initial_distance_run = 1;
  BearingSimTruth truth;
  BearingLog log = SimulateBearingLog(o, &truth);
  log.source = "robot";
  return log;
}

// The log with every encoder sample changed by `change`.
BearingLog Changed(BearingLog log, const std::function<void(EncoderSample*)>& change) {
  for (BearingRun& run : log.runs) {
    for (EncoderSample& s : run.odometry) change(&s);
  }
  return log;
}

void ExpectRefused(const BearingLog& log, const std::vector<std::string>& words) {
  const StatusOr<BearingCalibrationResult> r = CalibrateBearing(log);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), StatusCode::kInvalidInput);
  for (const std::string& word : words) {
    EXPECT_NE(r.message().find(word), std::string::npos) << r.message() << "\nlacks: " << word;
  }
}

TEST(BearingInputChecks, TheLogAsRecordedPasses) {
  const StatusOr<BearingCalibrationResult> r = CalibrateBearing(Simulated());
  ASSERT_TRUE(r.ok()) << r.message();
  EXPECT_TRUE(r->has_metric);
}

TEST(BearingInputChecks, AWheelOfTheWrongSignIsNamed) {
  const BearingLog log = Simulated();
  ExpectRefused(Changed(log, [](EncoderSample* s) { s->left_rad = -s->left_rad; }),
                {"robot: the left wheel's readings have the wrong sign", "negate the left column"});
  ExpectRefused(Changed(log, [](EncoderSample* s) { s->right_rad = -s->right_rad; }),
                {"the right wheel's readings have the wrong sign", "negate the right column"});
  ExpectRefused(Changed(log,
                        [](EncoderSample* s) {
                          s->left_rad = -s->left_rad;
                          s->right_rad = -s->right_rad;
                        }),
                {"turns the other way than its wheels say", "both wheels"});
}

TEST(BearingInputChecks, WheelRotationInAnotherUnitIsNamed) {
  const BearingLog log = Simulated();
  ExpectRefused(Changed(log,
                        [](EncoderSample* s) {
                          s->left_rad *= 180.0 / M_PI;
                          s->right_rad *= 180.0 / M_PI;
                        }),
                {"looks like degrees"});
  ExpectRefused(Changed(log,
                        [](EncoderSample* s) {
                          s->left_rad = std::round(s->left_rad * 4096.0 / (2.0 * M_PI));
                          s->right_rad = std::round(s->right_rad * 4096.0 / (2.0 * M_PI));
                        }),
                {"looks like encoder ticks, about 40", "per wheel turn"});
}

// Swapped, the log is fitted as well by wheels five times their nominal size and a camera turned
// by 70°: the corrections say it, and the columns exchanged give a robot.
TEST(BearingInputChecks, SwappedWheelColumnsAreNamed) {
  ExpectRefused(WithWheelsSwapped(Simulated()),
                {"left and right wheel columns look swapped", "exchange the two columns"});
}

// Wheels far from meta.json's nominal that no other reading explains: the nominal or its unit.
TEST(BearingInputChecks, ANominalFarFromTheWheelsIsNamed) {
  BearingLog log = Simulated();
  log.meta.wheel_radius_m *= 3.0;
  log.meta.wheelbase_m *= 3.0;
  ExpectRefused(log, {"check meta.json's values and units"});
}

}  // namespace
}  // namespace calib
