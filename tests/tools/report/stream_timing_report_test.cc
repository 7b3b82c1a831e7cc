// The timing diagnostics in the calibrate JSON and summary.
#include <calib/tools/report/bearing_report.h>
#include <calib/tools/report/laser_report.h>
#include <calib/tools/report/stream_timing_report.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace calib {
namespace {

std::vector<StreamTiming> TwoStreams() {
  std::vector<double> stamps, values;
  for (int k = 0; k < 200; ++k) {
    stamps.push_back(0.1 * k);
    values.push_back(0.01 * k);
  }
  StreamTiming odometry = AnalyzeStreamTiming(stamps, values, "odometry", "dir/odometry.csv");
  StreamTiming poses = odometry;
  poses.stream = "sensor_poses";
  poses.source = "dir/sensor_poses.csv";
  poses.jitter_s = 0.017;
  poses.stamps_are_sample_times = false;
  poses.notes.push_back("dir/sensor_poses.csv: they are pick-up times, not sample times.");
  return {odometry, poses};
}

TEST(StreamTimingReportTest, JsonHoldsEveryStreamAndField) {
  const std::vector<StreamTiming> streams = TwoStreams();
  const nlohmann::json json = StreamTimingJson(streams);
  ASSERT_EQ(json.size(), 2u);
  EXPECT_EQ(json[0]["stream"], "odometry");
  EXPECT_EQ(json[0]["source"], "dir/odometry.csv");
  EXPECT_EQ(json[0]["records"], 200);
  EXPECT_EQ(json[0]["samples"], 200);
  EXPECT_EQ(json[0]["duplicates_dropped"], 0);
  EXPECT_NEAR(json[0]["period_s"].get<double>(), 0.1, 1e-12);
  EXPECT_EQ(json[0]["regular"], true);
  EXPECT_EQ(json[0]["stamps_are_sample_times"], true);
  EXPECT_EQ(json[1]["jitter_s"], 0.017);
  EXPECT_EQ(json[1]["stamps_are_sample_times"], false);
  for (const char* key :
       {"repeated_values", "gaps", "longest_gap_s", "multiple_fraction", "free_running_signature",
        "interval_correlation", "pickup_scatter_s", "step_multiple_fraction", "notes"}) {
    EXPECT_TRUE(json[1].contains(key)) << key;
  }
  EXPECT_EQ(json[1]["notes"].back(), streams[1].notes.back());
}

TEST(StreamTimingReportTest, CalibrateJsonAndSummaryCarryTheTimingOnlyWhenGiven) {
  const std::vector<StreamTiming> streams = TwoStreams();
  const LaserCalibrationResult laser;
  EXPECT_FALSE(LaserResultJson(laser, "in", "cauchy").contains("timing"));
  const nlohmann::ordered_json json = LaserResultJson(laser, "in", "cauchy", streams);
  ASSERT_TRUE(json.contains("timing"));
  EXPECT_EQ(json["timing"]["streams"].size(), 2u);
  EXPECT_EQ(json["timing"]["streams"][1]["stream"], "sensor_poses");
  const std::string text = LaserResultSummary(laser, "in", "cauchy", streams);
  EXPECT_NE(text.find("timing of dir/odometry.csv: 200 samples, period 100 ms"), std::string::npos)
      << text;
  EXPECT_NE(text.find("stamps are NOT sample times"), std::string::npos) << text;
  EXPECT_NE(text.find("pick-up times, not sample times"), std::string::npos) << text;
  EXPECT_EQ(LaserResultSummary(laser, "in", "cauchy").find("timing of"), std::string::npos);

  const BearingCalibrationResult bearing;
  EXPECT_FALSE(BearingResultJson(bearing, "in", "cauchy").contains("timing"));
  EXPECT_EQ(BearingResultJson(bearing, "in", "cauchy", streams)["timing"]["streams"].size(), 2u);
  EXPECT_NE(BearingResultSummary(bearing, "in", "cauchy", streams).find("timing of"),
            std::string::npos);
}

}  // namespace
}  // namespace calib
