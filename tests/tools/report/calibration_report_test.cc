// calibrate's report, one assembly for the command line and Python: the model screen runs on
// logs up to its limit and says so beyond it; started beside the calibration, it reports the same.
#include <calib/core/laser/laser_log_io.h>
#include <calib/tools/report/calibration_report.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <memory>
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

// l90's screen finds physics the base model leaves out: the report must say the same whether the
// screen ran beside the calibration (on its own or waiting for the calibration's closed forms) or
// after it.
TEST(CalibrationReportTest, AScreenStartedBesideTheCalibrationReportsTheSame) {
  const std::filesystem::path l90 = std::filesystem::path(CALIB_CENSI_DATA_DIR) / "l90.tuple";
  if (!std::filesystem::exists(l90)) {
    GTEST_SKIP() << "the published recordings are not at " << l90.parent_path()
                 << " (they are not part of the repository)";
  }
  const StatusOr<LaserLog> log = ReadLaserLog(l90.string());
  ASSERT_TRUE(log.ok()) << log.message();
  LaserReportOptions options;
  options.input = l90.string();
  LaserReportOptions started = options;
  started.started_screen = StartLaserModelScreen(log->intervals, started);
  ASSERT_TRUE(started.started_screen.valid());
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log->intervals);
  ASSERT_TRUE(result.ok()) << result.message();
  const CalibrationReport after = LaserIntervalReport(*result, {&*log}, options);
  const CalibrationReport beside = LaserIntervalReport(*result, {&*log}, started);
  EXPECT_TRUE(after.json["model_screen"]["flagged"].get<bool>());
  EXPECT_EQ(beside.json.dump(), after.json.dump());
  EXPECT_EQ(beside.summary, after.summary);

  // Waiting for the calibration's closed forms (as `calib calibrate` starts it): the same again.
  {
    LaserReportOptions waiting = options;
    LaserCalibrationOptions calibration;
    ScreenClosedForms closed_forms;
    waiting.calibration_closed_forms = closed_forms.future();
    calibration.closed_forms_done = closed_forms.Giver();
    waiting.started_screen = StartLaserModelScreen(log->intervals, waiting);
    const StatusOr<LaserCalibrationResult> handing = CalibrateLaser(log->intervals, calibration);
    ASSERT_TRUE(handing.ok()) << handing.message();
    const CalibrationReport handed = LaserIntervalReport(*handing, {&*log}, waiting);
    EXPECT_EQ(handed.json.dump(), LaserIntervalReport(*handing, {&*log}, options).json.dump());
  }
  // Released without them (the calibration stopped first): the screen computes its own.
  {
    LaserReportOptions released = options;
    auto closed_forms = std::make_unique<ScreenClosedForms>();
    released.calibration_closed_forms = closed_forms->future();
    released.started_screen = StartLaserModelScreen(log->intervals, released);
    closed_forms.reset();
    EXPECT_EQ(LaserIntervalReport(*result, {&*log}, released).json.dump(), after.json.dump());
  }

  // Beyond the limit nothing is started: the report says it did not run.
  options.screen_max_intervals = 100;
  EXPECT_FALSE(StartLaserModelScreen(log->intervals, options).valid());
}

}  // namespace
}  // namespace calib
