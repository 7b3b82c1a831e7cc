// The deployable forms of a calibration: the numbers a robot's configuration takes.
#include <calib/tools/report/deployment.h>
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>
#include <vector>

namespace calib {
namespace {

LaserCalibrationResult Result() {
  LaserCalibrationResult r;
  r.estimate.odometry = OdometryParams{0.0990, 0.1010, 0.52};
  r.estimate.base_T_sensor = Pose2d(0.21, -0.03, 0.4);
  r.stddev << 1e-4, 2e-4, 3e-4, 4e-4, 5e-4, 6e-4;
  return r;
}

// The value after "key: " on its line (first occurrence).
double YamlValue(const std::string& yaml, const std::string& key) {
  const size_t at = yaml.find("\n" + key + ": ");
  EXPECT_NE(at, std::string::npos) << key;
  return std::stod(yaml.substr(at + key.size() + 3));
}

std::vector<std::string> Fields(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  for (std::string f; in >> f;) out.push_back(f);
  return out;
}

TEST(DeploymentTest, DiffDriveParametersReproduceEachWheel) {
  const Deployment d = LaserDeployment(Result(), "log.tuple");
  const std::string yaml = DeploymentYaml(d);
  const double r = YamlValue(yaml, "wheel_radius");
  EXPECT_NEAR(r, 0.1, 1e-9);
  EXPECT_NEAR(YamlValue(yaml, "wheel_separation"), 0.52, 1e-9);
  EXPECT_NEAR(YamlValue(yaml, "    left_wheel_radius_multiplier") * r, 0.0990, 1e-6);
  EXPECT_NEAR(YamlValue(yaml, "    right_wheel_radius_multiplier") * r, 0.1010, 1e-6);
  EXPECT_NE(yaml.find("± 0.000300 m (1σ)"), std::string::npos) << yaml;
  EXPECT_EQ(yaml.find("sensor_time_offset"), std::string::npos);  // Not estimated.
}

TEST(DeploymentTest, StaticTransformAndUrdfCarryTheMounting) {
  const Deployment d = LaserDeployment(Result(), "log.tuple");
  const std::vector<std::string> f = Fields(DeploymentStaticTransform(d));
  ASSERT_EQ(f.size(), 8u);
  EXPECT_DOUBLE_EQ(std::stod(f[0]), 0.21);
  EXPECT_DOUBLE_EQ(std::stod(f[1]), -0.03);
  EXPECT_DOUBLE_EQ(std::stod(f[2]), 0.0);
  EXPECT_DOUBLE_EQ(std::stod(f[3]), 0.4);  // yaw pitch roll.
  EXPECT_EQ(f[6], "base_link");
  EXPECT_EQ(f[7], "laser");
  const std::string urdf = DeploymentUrdf(d);
  EXPECT_NE(urdf.find("<origin xyz=\"0.210000 -0.030000 0.000000\" rpy=\"0.000000 0.000000 "
                      "0.400000\"/>"),
            std::string::npos)
      << urdf;
}

// An upside-down sensor in tf (roll π, 12 cm up): the calibrated x, y and yaw replace tf's, the
// height and the roll stay.
TEST(DeploymentTest, TfHeightAndRollAreKept) {
  RobotBagLog recording;
  recording.base_frame = "base_footprint";
  recording.sensor_frame = "lidar";
  PlanarMounting nominal;
  nominal.base_T_sensor_3d.translation() = Eigen::Vector3d(0.2, 0.0, 0.12);
  nominal.base_T_sensor_3d.linear() = (Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitZ()) *
                                       Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()))
                                          .toRotationMatrix();
  nominal.base_T_sensor = Pose2d(0.2, 0.0, 0.35);
  nominal.upside_down = true;
  recording.nominal_mounting = nominal;
  const Deployment d = LaserDeployment(Result(), "run.mcap", &recording);
  const std::vector<std::string> f = Fields(DeploymentStaticTransform(d));
  ASSERT_EQ(f.size(), 8u);
  EXPECT_DOUBLE_EQ(std::stod(f[0]), 0.21);
  EXPECT_DOUBLE_EQ(std::stod(f[2]), 0.12);
  EXPECT_NEAR(std::stod(f[3]), 0.4, 1e-6);
  EXPECT_NEAR(std::stod(f[4]), 0.0, 1e-6);
  EXPECT_NEAR(std::abs(std::stod(f[5])), M_PI, 1e-6);
  EXPECT_EQ(f[6], "base_footprint");
  EXPECT_EQ(f[7], "lidar");
  EXPECT_NE(DeploymentYaml(d).find("from tf"), std::string::npos);
}

TEST(DeploymentTest, TimeOffsetOnlyForAClockThatAnOffsetExpresses) {
  LaserTimingResult timing;
  timing.sensor_clock = "stamps";
  timing.time_offset_s = -0.0186;
  timing.time_offset_stddev_s = 0.0005;
  Deployment d = LaserDeployment(Result(), "run.mcap", nullptr, &timing);
  EXPECT_NEAR(YamlValue(DeploymentYaml(d), "sensor_time_offset"), -0.0186, 1e-9);
  timing.sensor_clock = "free_running";
  d = LaserDeployment(Result(), "run.mcap", nullptr, &timing);
  EXPECT_FALSE(d.time_offset_s.has_value());
  EXPECT_NE(DeploymentYaml(d).find("free-runs"), std::string::npos);
}

TEST(DeploymentTest, BearingNeedsTheMetricScale) {
  BearingCalibrationResult result;
  BearingLog log;
  log.meta.wheel_radius_m = 0.3;
  log.meta.wheelbase_m = 0.5;
  EXPECT_NE(BearingDeployment(result, log, "dir").message().find("initial distance"),
            std::string::npos);
  result.has_metric = true;
  result.metric = BearingMetricParams{0.1, 0.3, M_PI / 2, 0.99, 1.006, 0.97};
  const StatusOr<Deployment> d = BearingDeployment(result, log, "dir");
  ASSERT_TRUE(d.ok()) << d.message();
  EXPECT_NEAR(d->right_wheel_radius_m, 0.297, 1e-12);
  EXPECT_NEAR(d->left_wheel_radius_m, 0.3018, 1e-12);
  EXPECT_NEAR(d->wheel_separation_m, 0.485, 1e-12);
  EXPECT_NEAR(d->base_T_sensor.translation().x(), 0.3 * std::cos(0.1), 1e-12);
  EXPECT_NEAR(d->base_T_sensor.translation().y(), 0.3 * std::sin(0.1), 1e-12);
  const std::vector<std::string> f = Fields(DeploymentStaticTransform(*d));
  EXPECT_NEAR(std::stod(f[3]), 0.1 + M_PI / 2, 1e-6);
}

TEST(DeploymentTest, ExportFormats) {
  EXPECT_EQ(*ParseExportFormats("yaml,tf,yaml"), (std::vector<std::string>{"yaml", "tf"}));
  EXPECT_EQ(*ParseExportFormats("all"), (std::vector<std::string>{"yaml", "urdf", "tf"}));
  EXPECT_TRUE(ParseExportFormats("")->empty());
  EXPECT_NE(ParseExportFormats("yaml,json").message().find("'json'"), std::string::npos);
}

}  // namespace
}  // namespace calib
