// The laser report's JSON pieces that a user of the C++ API writes without the CLI.
#include <calib/tools/report/laser_report.h>
#include <gtest/gtest.h>

namespace calib {
namespace {

TEST(LaserReportTest, SimulationTruthHasTheResultsParameterNames) {
  LaserSimOptions options;
  options.num_intervals = 10;
  options.effects.time_offset_s = 0.02;
  LaserSimTruth truth;
  SimulateLaserLog(options, &truth);
  const nlohmann::ordered_json json = LaserSimTruthJson(truth);
  EXPECT_EQ(json["problem"], "laser");
  EXPECT_EQ(json["estimate"]["r_l"], truth.odometry.left_radius_m);
  EXPECT_EQ(json["estimate"]["b"], truth.odometry.wheelbase_m);
  EXPECT_EQ(json["estimate"]["sensor_theta"], truth.base_T_sensor(2));
  EXPECT_EQ(json["effects"]["time_offset"], 0.02);
  EXPECT_EQ(json["effects"]["wheel_radius_change"], -1.0);
  int i = 0;
  for (const auto& [name, value] : json["estimate"].items()) {
    EXPECT_EQ(name, kLaserParamNames[i++]);
  }
  EXPECT_EQ(i, kNumLaserParams);
}

// A refinement that stopped before converging says so in the JSON and in the summary.
TEST(LaserReportTest, ConvergenceAndWarningsReachTheJson) {
  LaserCalibrationResult result;
  result.converged = false;
  result.warnings = {"the refinement stopped without converging"};
  result.observability.warnings = result.warnings;
  const nlohmann::ordered_json json = LaserResultJson(result, "sim", "cauchy");
  EXPECT_EQ(json["converged"], false);
  EXPECT_EQ(json["observability"]["warnings"][0], result.warnings[0]);
  const std::string text = LaserResultSummary(result, "sim", "cauchy");
  EXPECT_NE(text.find("warning: the refinement stopped"), std::string::npos) << text;
}

// Without a robust loss there are no inliers to count: every interval weighs fully.
TEST(LaserReportTest, NoLossSaysEveryIntervalWeighsFully) {
  LaserCalibrationResult result;
  result.samples = 100;
  result.inliers = 97;
  EXPECT_NE(LaserResultSummary(result, "sim", "cauchy").find("inliers 97 of 100"),
            std::string::npos);
  const std::string text = LaserResultSummary(result, "sim", "none");
  EXPECT_EQ(text.find("inliers 97"), std::string::npos) << text;
  EXPECT_NE(text.find("all 100 intervals weigh fully (no robust loss); 3 lie beyond"),
            std::string::npos)
      << text;
}

}  // namespace
}  // namespace calib
