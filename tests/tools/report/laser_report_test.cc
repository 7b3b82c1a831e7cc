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

}  // namespace
}  // namespace calib
