// calibrate's report, one assembly for the command line and Python: the model screen runs on
// logs up to its limit and says so beyond it.
#include <calib/core/laser/laser_log_io.h>
#include <calib/tools/report/calibration_report.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace calib {
namespace {

TEST(CalibrationReportTest, TheModelScreenRunsUpToItsLimitAndSaysSoBeyond) {
  const std::string path =
      (std::filesystem::path(CALIB_SOURCE_DIR) / "data" / "sample_laser.tuple").string();
  const StatusOr<LaserLog> log = ReadLaserLog(path);
  ASSERT_TRUE(log.ok()) << log.message();
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log->intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  LaserReportOptions options;
  options.input = path;
  CalibrationReport report = LaserIntervalReport(*result, {&*log}, options);
  EXPECT_FALSE(report.json["model_screen"]["flagged"].get<bool>());
  EXPECT_EQ(report.json["verdict"], "trusted");
  EXPECT_TRUE(report.json.contains("odometry_drift"));

  options.screen_max_intervals = 100;
  report = LaserIntervalReport(*result, {&*log}, options);
  EXPECT_TRUE(report.json["model_screen"].contains("skipped"));
  EXPECT_NE(report.summary.find("model screen: not run on 2000 intervals (more than 100)"),
            std::string::npos)
      << report.summary;
  EXPECT_EQ(report.json["verdict"], "trusted");  // Not run is not a finding.
}

}  // namespace
}  // namespace calib
