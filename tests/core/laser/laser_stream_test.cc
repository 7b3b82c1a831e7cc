// The stream reader's duplicate handling and timing diagnostics.
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/scratch_dir.h"

namespace calib {
namespace {

namespace fs = std::filesystem;

class LaserStreamReadTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::MakeScratchDir("laser_stream_"); }
  void TearDown() override { fs::remove_all(dir_); }
  void Write(const std::string& odometry, const std::string& poses) {
    std::ofstream(dir_ / "odometry.csv") << odometry;
    std::ofstream(dir_ / "sensor_poses.csv") << poses;
  }
  fs::path dir_;
};

TEST_F(LaserStreamReadTest, ExactDuplicatesAreDroppedWithACount) {
  Write("t,left,right\n0,0,0\n0.02,0.1,0.1\n0.02,0.1,0.1\n0.04,0.2,0.2\n0.06,0.3,0.3\n",
        "t,x,y,theta\n0.01,0,0,0\n0.01,0,0,0\n0.01,0,0,0\n0.05,0.1,0,0\n");
  std::vector<StreamTiming> timing;
  const StatusOr<LaserStreams> streams = ReadLaserStreamSamples(dir_.string(), &timing);
  ASSERT_TRUE(streams.ok()) << streams.message();
  ASSERT_EQ(streams->odometry.size(), 4u);
  EXPECT_EQ(streams->odometry[2].t_s, 0.04);
  EXPECT_EQ(streams->odometry[2].line, 5);
  ASSERT_EQ(streams->sensor_poses.size(), 2u);
  EXPECT_EQ(streams->sensor_poses[1].line, 5);
  EXPECT_EQ(streams->sensor_poses[1].world_T_sensor(0), 0.1);
  ASSERT_EQ(timing.size(), 2u);
  EXPECT_EQ(timing[0].stream, "odometry");
  EXPECT_EQ(timing[0].source, (dir_ / "odometry.csv").string());
  EXPECT_EQ(timing[0].records, 5);
  EXPECT_EQ(timing[0].samples, 4);
  EXPECT_EQ(timing[0].duplicates_dropped, 1);
  EXPECT_NEAR(timing[0].period_s, 0.02, 1e-12);
  EXPECT_EQ(timing[1].stream, "sensor_poses");
  EXPECT_EQ(timing[1].records, 4);
  EXPECT_EQ(timing[1].duplicates_dropped, 2);
  EXPECT_TRUE(ReadLaserStreamSamples(dir_.string(), nullptr).ok());

  const StatusOr<LaserLog> log = ReadLaserLog(dir_.string());
  ASSERT_TRUE(log.ok()) << log.message();
  ASSERT_EQ(log->intervals.size(), 1u);
  EXPECT_EQ(log->intervals[0].line, 2);
  EXPECT_NEAR(log->intervals[0].left_speed, 5.0, 1e-12);
  EXPECT_EQ(log->streams.odometry.size(), 4u);
  EXPECT_EQ(log->stream_timing.size(), 2u);
  EXPECT_EQ(log->stream_timing[1].duplicates_dropped, 2);
}

TEST_F(LaserStreamReadTest, RepeatedStampWithOtherValuesNamesBothLines) {
  Write("t,left,right\n0,0,0\n0.02,0.1,0.1\n0.02,0.1,0.15\n0.04,0.2,0.2\n",
        "t,x,y,theta\n0.01,0,0,0\n0.03,0,0,0\n");
  const StatusOr<LaserLog> log = ReadLaserStream(dir_.string());
  ASSERT_FALSE(log.ok());
  EXPECT_EQ(log.status().code(), StatusCode::kInvalidInput);
  EXPECT_NE(log.message().find("odometry.csv: line 3 and line 4 share t=0.02 but differ in right"),
            std::string::npos)
      << log.message();
}

// A pose repeated under a later stamp (a logger picking up the same sample again) is no interval
// of its own: the interval runs from its first pick-up to the next sample, as the timing's
// samples do. As an interval it had no motion over a pick-up period of turning wheels.
TEST_F(LaserStreamReadTest, HeldRepeatsAreNoIntervals) {
  Write("t,left,right\n0,0,0\n0.02,0.1,0.1\n0.04,0.2,0.2\n0.06,0.3,0.3\n0.08,0.4,0.4\n",
        "t,x,y,theta\n0.01,0,0,0\n0.03,0.1,0,0\n0.05,0.1,0,0\n0.07,0.2,0,0\n");
  const StatusOr<LaserLog> log = ReadLaserLog(dir_.string());
  ASSERT_TRUE(log.ok()) << log.message();
  ASSERT_EQ(log->intervals.size(), 2u);
  EXPECT_EQ(log->intervals[1].line, 3);
  EXPECT_NEAR(log->intervals[1].start_s, 0.03, 1e-12);
  EXPECT_NEAR(log->intervals[1].duration_s, 0.04, 1e-12);
  EXPECT_NEAR(log->intervals[1].sensor_motion(0), 0.1, 1e-12);
  EXPECT_NEAR(log->intervals[1].left_speed, 5.0, 1e-9);
  // A sensor that never moves gives no interval at all, and says so.
  Write("t,left,right\n0,0,0\n0.02,0.1,0.1\n0.04,0.2,0.2\n",
        "t,x,y,theta\n0.01,1,2,0\n0.03,1,2,0\n");
  const StatusOr<LaserLog> still = ReadLaserLog(dir_.string());
  ASSERT_FALSE(still.ok());
  EXPECT_NE(still.message().find("sensor_poses.csv: every sensor pose"), std::string::npos)
      << still.message();
}

// The simulator's streams: encoder polls on a regular grid, scan poses at its irregular but
// exact interval ends. Both are sample times, neither shows a free-running signature.
TEST_F(LaserStreamReadTest, SimulatedStreamsAreSampleTimes) {
  LaserSimOptions options;
  options.num_intervals = 400;
  const LaserStreams streams = SimulateLaserStreams(options, 50.0);
  const StatusOr<LaserLog> log = LaserLogFromStreams(streams.odometry, streams.sensor_poses, "sim");
  ASSERT_TRUE(log.ok()) << log.message();
  EXPECT_EQ(log->streams.odometry.size(), streams.odometry.size());
  EXPECT_EQ(log->streams.sensor_poses.size(), streams.sensor_poses.size());
  ASSERT_EQ(log->stream_timing.size(), 2u);
  const StreamTiming& odometry = log->stream_timing[0];
  EXPECT_NEAR(odometry.period_s, 0.02, 1e-6);
  EXPECT_TRUE(odometry.regular);
  const StreamTiming& poses = log->stream_timing[1];
  EXPECT_EQ(poses.source, "sim (sensor poses)");
  EXPECT_NEAR(poses.period_s, options.mean_interval_s, 0.01);
  for (const StreamTiming& t : log->stream_timing) {
    SCOPED_TRACE(t.stream);
    EXPECT_EQ(t.duplicates_dropped, 0);
    EXPECT_FALSE(t.free_running_signature);
    EXPECT_TRUE(t.stamps_are_sample_times);
  }
}

}  // namespace
}  // namespace calib
