// The common input mistakes, each made on a correct simulated log: the check names the mistake
// and what to do, and never lets a wrong number through; the correct log and the published
// recordings pass without a word.
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/core/laser/wheel_readings.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/laser/censi_closed_form.h>
#include <calib/solvers/laser/laser_input_checks.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

namespace calib {
namespace {

namespace fs = std::filesystem;

constexpr double kTicksPerRev = 2048.0;

LaserSimOptions Simulation() {
  LaserSimOptions options;
  options.num_intervals = 400;
  return options;
}

LaserLog GoodLog() {
  LaserLog log = SimulateLaserLog(Simulation());
  log.source = "robot.csv";
  return log;
}

// The streams of the same motion, read back as a directory is (encoders at 50 Hz).
LaserLog GoodStreamLog(LaserStreams* streams = nullptr) {
  const LaserStreams s = SimulateLaserStreams(Simulation(), 50.0);
  if (streams != nullptr) *streams = s;
  StatusOr<LaserLog> log = LaserLogFromStreams(s.odometry, s.sensor_poses, "robot_streams");
  EXPECT_TRUE(log.ok()) << log.message();
  return *log;
}

// Expects the check to refuse with a message holding every needle.
void ExpectRefused(const LaserLog& log, const std::vector<std::string>& needles,
                   const std::vector<std::string>& absent = {}) {
  const Status status = CheckLaserInput(log);
  ASSERT_FALSE(status.ok()) << "accepted " << log.source;
  EXPECT_EQ(status.code(), StatusCode::kInvalidInput);
  for (const std::string& needle : needles) {
    EXPECT_NE(status.message().find(needle), std::string::npos)
        << "lacks '" << needle << "': " << status.message();
  }
  for (const std::string& needle : absent) {
    EXPECT_EQ(status.message().find(needle), std::string::npos)
        << "holds '" << needle << "': " << status.message();
  }
}

TEST(LaserInputChecksTest, CorrectLogsPass) {
  const LaserLog log = GoodLog();
  EXPECT_TRUE(CheckLaserInput(log).ok()) << CheckLaserInput(log).message();
  EXPECT_TRUE(log.warnings.empty());
  const LaserLog streams = GoodStreamLog();
  EXPECT_TRUE(CheckLaserInput(streams).ok()) << CheckLaserInput(streams).message();
  EXPECT_TRUE(streams.warnings.empty());
}

// The check's consensus screen is the one the calibration computes: handed over, it gives the
// same screen and the same estimate (on a log with slips, which the screen removes).
TEST(LaserInputChecksTest, TheConsensusScreenIsHandedToTheCalibration) {
  LaserSimOptions simulation = Simulation();
  simulation.num_intervals = 600;
  simulation.outlier_fraction = 0.1;
  const LaserLog log = SimulateLaserLog(simulation);
  std::shared_ptr<const ConsensusScreen> screen;
  LaserInputCheckOptions check;
  check.consensus_screen = &screen;
  ASSERT_TRUE(CheckLaserInput(log, check).ok());
  ASSERT_NE(screen, nullptr);
  EXPECT_GT(screen->outliers(), 0);
  EXPECT_EQ(screen->kept, ScreenGrossIntervals(log.intervals).kept);

  LaserCalibrationOptions options;
  options.interval_jitter = false;
  const StatusOr<LaserCalibrationResult> computed = CalibrateLaser(log.intervals, options);
  options.consensus_screen = screen;
  const StatusOr<LaserCalibrationResult> reused = CalibrateLaser(log.intervals, options);
  ASSERT_TRUE(computed.ok() && reused.ok());
  EXPECT_EQ(reused->gross_intervals, computed->gross_intervals);
  EXPECT_EQ(reused->estimate.ToVector(), computed->estimate.ToVector());

  // A screen of other intervals (another count) is not used.
  const std::vector<LaserInterval> fewer(log.intervals.begin(), log.intervals.end() - 10);
  const StatusOr<LaserCalibrationResult> other = CalibrateLaser(fewer, options);
  options.consensus_screen = nullptr;
  const StatusOr<LaserCalibrationResult> fresh = CalibrateLaser(fewer, options);
  ASSERT_TRUE(other.ok() && fresh.ok());
  EXPECT_EQ(other->estimate.ToVector(), fresh->estimate.ToVector());
}

TEST(LaserInputChecksTest, TicksAreRefusedWithTheConversionAndConvertedExactly) {
  LaserLog log = GoodLog();
  const CensiClosedFormResult truth = *CensiClosedForm(log.intervals);
  for (LaserInterval& interval : log.intervals) {
    interval.left_speed *= kTicksPerRev / (2.0 * M_PI);
    interval.right_speed *= kTicksPerRev / (2.0 * M_PI);
  }
  ExpectRefused(log, {"robot.csv", "wheel radius comes out at 0.0", "encoder ticks",
                      "--ticks_per_rev N", "N/2π"});
  ASSERT_TRUE(ConvertWheelTicks(kTicksPerRev, &log).ok());
  EXPECT_TRUE(CheckLaserInput(log).ok());
  const CensiClosedFormResult converted = *CensiClosedForm(log.intervals);
  EXPECT_NEAR(converted.calibration.odometry.left_radius_m,
              truth.calibration.odometry.left_radius_m, 1e-12);
  EXPECT_NEAR(converted.calibration.odometry.wheelbase_m, truth.calibration.odometry.wheelbase_m,
              1e-12);
  EXPECT_FALSE(ConvertWheelTicks(0.0, &log).ok());
}

// T in milliseconds makes the wheel rotation (speed × T) a thousand times too large, as ticks
// would: the durations say which, before the wheels are looked at.
TEST(LaserInputChecksTest, DurationsInMillisecondsAreNamedNotTakenForTicks) {
  LaserLog log = GoodLog();
  for (LaserInterval& interval : log.intervals) {
    ASSERT_TRUE(interval.steps.empty());  // A tuple's interval: wheel speeds and T.
    interval.duration_s *= 1e3;
  }
  ExpectRefused(log, {"robot.csv (the intervals' T, summed)", "milliseconds (divide T by 1e+03)"});
}

TEST(LaserInputChecksTest, TicksInStreamsAreConvertedInTheSamplesToo) {
  LaserStreams streams;
  GoodStreamLog(&streams);
  for (EncoderSample& s : streams.odometry) {
    s.left_rad *= kTicksPerRev / (2.0 * M_PI);
    s.right_rad *= kTicksPerRev / (2.0 * M_PI);
  }
  StatusOr<LaserLog> log = LaserLogFromStreams(streams.odometry, streams.sensor_poses, "robot_dir");
  ASSERT_TRUE(log.ok()) << log.message();
  ExpectRefused(*log, {"robot_dir", "the left and right columns of odometry.csv", "encoder ticks"});
  ASSERT_TRUE(ConvertWheelTicks(kTicksPerRev, &*log).ok());
  EXPECT_TRUE(CheckLaserInput(*log).ok());
  EXPECT_NEAR(log->streams.odometry.back().left_rad,
              streams.odometry.back().left_rad * 2.0 * M_PI / kTicksPerRev, 1e-12);
}

TEST(LaserInputChecksTest, ThetaInDegreesIsRefused) {
  LaserLog log = GoodLog();
  for (LaserInterval& interval : log.intervals) interval.sensor_motion(2) *= 180.0 / M_PI;
  ExpectRefused(log, {"sm_theta looks like degrees", "Convert sm_theta to radians", "more than π"},
                {"positive wheel speeds"});
}

TEST(LaserInputChecksTest, StreamHeadingsInDegreesAreRefused) {
  LaserStreams streams;
  GoodStreamLog(&streams);
  for (StampedPose& p : streams.sensor_poses) p.world_T_sensor(2) *= 180.0 / M_PI;
  const StatusOr<LaserLog> log =
      LaserLogFromStreams(streams.odometry, streams.sensor_poses, "robot_dir");
  ASSERT_TRUE(log.ok()) << log.message();
  ExpectRefused(*log, {"the theta column of sensor_poses.csv looks like degrees"},
                {"positive wheel speeds"});
}

// Swapped wheels fit as well as both wheels negated (the sensor heading differs by π): both are
// named with the heading each implies; one wheel negated is named alone.
TEST(LaserInputChecksTest, SwappedWheelsAreToldFromOneReversedWheel) {
  LaserLog swapped = GoodLog();
  for (LaserInterval& i : swapped.intervals) std::swap(i.left_speed, i.right_speed);
  ExpectRefused(swapped,
                {"turn the robot the wrong way", "phi_l and phi_r swapped", "both negated",
                 "sensor heading -8", "sensor heading 9"},
                {"wrong sign"});

  LaserLog left = GoodLog();
  for (LaserInterval& i : left.intervals) i.left_speed = -i.left_speed;
  ExpectRefused(left, {"the left wheel's readings have the wrong sign", "Negate phi_l"},
                {"swapped", "right wheel"});

  LaserLog right = GoodLog();
  for (LaserInterval& i : right.intervals) i.right_speed = -i.right_speed;
  ExpectRefused(right, {"the right wheel's readings have the wrong sign", "Negate phi_r"},
                {"swapped", "left wheel"});
}

TEST(LaserInputChecksTest, LengthsInMillimetresAreRefused) {
  LaserLog log = GoodLog();
  for (LaserInterval& i : log.intervals) i.sensor_motion.head<2>() *= 1000.0;
  ExpectRefused(log, {"sm_x and sm_y look like millimetres", "wheelbase comes out at 8"});

  LaserStreams streams;
  GoodStreamLog(&streams);
  for (StampedPose& p : streams.sensor_poses) p.world_T_sensor.head<2>() *= 1000.0;
  const StatusOr<LaserLog> stream_log =
      LaserLogFromStreams(streams.odometry, streams.sensor_poses, "robot_dir");
  ASSERT_TRUE(stream_log.ok()) << stream_log.message();
  ExpectRefused(*stream_log, {"the x and y columns of sensor_poses.csv look like millimetres"});
}

// Turns instead of radians make the radius 2π times larger: said where no wheel is that large.
TEST(LaserInputChecksTest, LargeWheelsInTurnsAreRefused) {
  LaserSimOptions options = Simulation();
  options.odometry = OdometryParams{0.6, 0.6, 1.5};
  options.base_T_sensor = Pose2d(0.3, 0.0, 0.0);
  LaserLog log = SimulateLaserLog(options);
  log.source = "big.csv";
  EXPECT_TRUE(CheckLaserInput(log).ok()) << CheckLaserInput(log).message();
  for (LaserInterval& i : log.intervals) {
    i.left_speed /= 2.0 * M_PI;
    i.right_speed /= 2.0 * M_PI;
  }
  ExpectRefused(log, {"big.csv: the wheel radius comes out at 3.7", "look like wheel turns",
                      "--ticks_per_rev 1"});
  ASSERT_TRUE(ConvertWheelTicks(1.0, &log).ok());
  EXPECT_TRUE(CheckLaserInput(log).ok());
}

// Cumulative angles reported wrapped into (−π, π] are unwrapped, with a warning; the log is then
// the correct one.
TEST(LaserInputChecksTest, WrappedWheelAnglesAreUnwrappedAndSaid) {
  LaserStreams streams;
  const LaserLog good = GoodStreamLog(&streams);
  for (EncoderSample& s : streams.odometry) {
    s.left_rad = std::remainder(s.left_rad, 2.0 * M_PI);
    s.right_rad = std::remainder(s.right_rad, 2.0 * M_PI);
  }
  const StatusOr<LaserLog> log =
      LaserLogFromStreams(streams.odometry, streams.sensor_poses, "robot_dir");
  ASSERT_TRUE(log.ok()) << log.message();
  ASSERT_EQ(log->warnings.size(), 1u);
  EXPECT_NE(log->warnings[0].find("jumps of 2π were unwrapped"), std::string::npos)
      << log->warnings[0];
  EXPECT_TRUE(CheckLaserInput(*log).ok());
  ASSERT_EQ(log->intervals.size(), good.intervals.size());
  for (size_t k = 0; k < good.intervals.size(); ++k) {
    ASSERT_NEAR(log->intervals[k].left_speed, good.intervals[k].left_speed, 1e-9) << k;
    ASSERT_NEAR(log->intervals[k].right_speed, good.intervals[k].right_speed, 1e-9) << k;
  }
}

TEST(LaserInputChecksTest, UnwrapLeavesCumulativeAnglesAlone) {
  std::vector<double> values = {0.0, 0.0, 3.0, 1.0, 6.5, 2.0};  // left 0, 3, 6.5: not wrapped.
  EXPECT_EQ(UnwrapWheelAngles(&values, 2, 0), 0);
  EXPECT_EQ(values[4], 6.5);
  std::vector<double> wrapped = {3.0, -3.0, -2.5};  // Wrapped into (−π, π].
  EXPECT_EQ(UnwrapWheelAngles(&wrapped, 1, 0), 1);
  EXPECT_NEAR(wrapped[1], 2.0 * M_PI - 3.0, 1e-12);
}

// An exact duplicate record (every value, t too) is dropped and counted, not an error.
TEST(LaserInputChecksTest, DuplicateCsvRecordsAreDroppedAndCounted) {
  const std::string header = "t,T,phi_l,phi_r,sm_x,sm_y,sm_theta\n";
  const std::string a = "0,0.8,0.4,0.5,0.008,0.0001,0.02\n";
  const std::string b = "0.8,0.8,0.3,0.5,0.007,0.0002,0.03\n";
  const std::string c = "1.6,0.8,0.3,0.6,0.007,0.0002,0.04\n";
  const StatusOr<LaserLog> log = ParseLaserCsv(header + a + b + b + c, "robot.csv");
  ASSERT_TRUE(log.ok()) << log.message();
  EXPECT_EQ(log->intervals.size(), 3u);
  EXPECT_FALSE(log->intervals[2].gap_before);
  ASSERT_EQ(log->warnings.size(), 1u);
  EXPECT_NE(log->warnings[0].find("robot.csv: 1 exact duplicate record(s) dropped (record 3"),
            std::string::npos)
      << log->warnings[0];
  // The same stamp with other values is still an overlap.
  EXPECT_FALSE(
      ParseLaserCsv(header + a + b + "0.8,0.8,0.3,0.5,0.007,0.0002,0.031\n" + c, "robot.csv").ok());

  const std::string tuple =
      R"({"T": 0.8, "phi_l": 0.4, "phi_r": 0.5, "sm": [0.008, 0.0001, 0.02]})";
  const StatusOr<LaserLog> tuples = ParseLaserTuples(tuple + " " + tuple + "\n", "robot.tuple");
  ASSERT_TRUE(tuples.ok()) << tuples.message();
  EXPECT_EQ(tuples->intervals.size(), 1u);
  EXPECT_EQ(tuples->warnings.size(), 1u);
}

TEST(LaserInputChecksTest, DuplicateStreamRecordsAreDroppedAndSaid) {
  LaserStreams streams;
  GoodStreamLog(&streams);
  streams.odometry.insert(streams.odometry.begin() + 30, streams.odometry[30]);
  streams.sensor_poses.insert(streams.sensor_poses.begin() + 10, streams.sensor_poses[10]);
  const StatusOr<LaserLog> log =
      LaserLogFromStreams(streams.odometry, streams.sensor_poses, "robot_dir");
  ASSERT_TRUE(log.ok()) << log.message();
  ASSERT_EQ(log->warnings.size(), 2u);
  EXPECT_NE(log->warnings[0].find("1 exact duplicate record(s) dropped"), std::string::npos);
  EXPECT_NE(log->warnings[1].find("sensor poses"), std::string::npos) << log->warnings[1];
  EXPECT_TRUE(CheckLaserInput(*log).ok());
}

// The published recordings (../shared/data/censi2013, several experiments concatenated, records
// sharing a line) raise no alarm.
TEST(LaserInputChecksTest, CensiRecordingsRaiseNoAlarm) {
  const fs::path dir = CALIB_CENSI_DATA_DIR;
  if (!fs::is_directory(dir)) GTEST_SKIP() << "the published recordings are not at " << dir;
  int files = 0;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".tuple") continue;
    ++files;
    const StatusOr<LaserLog> log = ReadLaserLog(entry.path().string());
    ASSERT_TRUE(log.ok()) << log.message();
    EXPECT_TRUE(log->warnings.empty()) << entry.path() << ": " << log->warnings.front();
    const Status status = CheckLaserInput(*log);
    EXPECT_TRUE(status.ok()) << status.message();
  }
  EXPECT_EQ(files, 12);
}

}  // namespace
}  // namespace calib
