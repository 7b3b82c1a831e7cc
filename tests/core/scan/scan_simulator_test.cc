#include <calib/core/bag/robot_messages_json.h>
#include <calib/core/diff_drive.h>
#include <calib/core/scan/scan_simulator.h>
#include <calib/core/se2.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace calib {
namespace {

ScanSimOptions MovingOptions() {
  ScanSimOptions options;
  options.laser.num_intervals = 30;
  options.beams = 360;
  options.sweep_s = 0.1;  // A full sweep between scans: the robot moves up to 5 cm meanwhile.
  options.range_max_m = 15.0;
  options.encoder_rate_hz = 1000.0;
  return options;
}

// Every return, put into the world from the sensor pose at its beam's time, lies on a wall.
TEST(ScanSimulatorTest, NoiseFreeReturnsLieOnWallsAtTheirBeamTimes) {
  const StatusOr<ScanSimulation> sim = SimulateScans(MovingOptions());
  ASSERT_TRUE(sim.ok()) << sim.status().message();
  ASSERT_EQ(sim->scans.size(), 31u);
  double worst = 0.0, worst_if_still = 0.0;
  int returns = 0;
  for (const LaserScan& scan : sim->scans) {
    EXPECT_NEAR(scan.time_increment_s, 0.1 / 360, 1e-15);
    for (int i = 0; i < static_cast<int>(scan.ranges_m.size()); ++i) {
      if (!scan.IsReturn(i)) continue;
      ++returns;
      const double r = scan.ranges_m[i];
      const Pose2d sensor =
          Compose(sim->truth.path.WorldTBase(scan.BeamTime(i)), sim->truth.base_T_sensor);
      const double a = sensor(2) + scan.BeamAngle(i);
      worst = std::max(worst, sim->world.DistanceTo(sensor.head<2>() +
                                                    r * Eigen::Vector2d(std::cos(a), std::sin(a))));
      // The same from the sweep's start pose, as if the robot stood still.
      const Pose2d start = sim->truth.world_T_sensor[scan.record];
      const double b = start(2) + scan.BeamAngle(i);
      worst_if_still = std::max(
          worst_if_still,
          sim->world.DistanceTo(start.head<2>() + r * Eigen::Vector2d(std::cos(b), std::sin(b))));
    }
  }
  EXPECT_GT(returns, 31 * 300);
  EXPECT_LT(worst, 1e-6);  // Float ranges below 16 m round by at most 1e-6 m.
  EXPECT_GT(worst_if_still, 1e-2);
}

// The encoders integrate to the true robot motion between scans.
TEST(ScanSimulatorTest, EncodersAndTruthPosesAgree) {
  const StatusOr<ScanSimulation> sim = SimulateScans(MovingOptions());
  ASSERT_TRUE(sim.ok()) << sim.status().message();
  const ScanSimTruth& truth = sim->truth;
  ASSERT_EQ(truth.world_T_sensor.size(), sim->scans.size());
  const OdometryParams& o = truth.odometry;
  Pose2d odometry = truth.path.WorldTBase(sim->encoders.front().t_s);
  double worst = 0.0, travelled = 0.0;
  for (size_t j = 1; j < sim->encoders.size(); ++j) {
    const EncoderSample& a = sim->encoders[j - 1];
    const EncoderSample& b = sim->encoders[j];
    odometry = Compose(odometry,
                       WheelStepDisplacement(o.left_radius_m, o.right_radius_m, o.wheelbase_m,
                                             b.left_rad - a.left_rad, b.right_rad - a.right_rad));
    const Pose2d exact = truth.path.WorldTBase(b.t_s);
    worst = std::max(worst, (odometry.head<2>() - exact.head<2>()).norm());
    travelled = exact.head<2>().norm();
  }
  EXPECT_GT(travelled, 0.2);
  EXPECT_LT(worst, 1e-5);
  for (size_t k = 0; k < sim->scans.size(); ++k) {
    EXPECT_EQ(sim->scans[k].stamp_s, truth.sweep_start_s[k]);
    const Pose2d expected =
        Compose(truth.path.WorldTBase(truth.sweep_start_s[k]), truth.base_T_sensor);
    EXPECT_LT((truth.world_T_sensor[k] - expected).norm(), 1e-12);
  }
}

TEST(ScanSimulatorTest, NoiseAndMissingReturnsAsAsked) {
  ScanSimOptions options = MovingOptions();
  options.beams = 1081;
  options.field_of_view_rad = 1.5 * M_PI;
  const StatusOr<ScanSimulation> clean = SimulateScans(options);
  options.range_noise_sigma_m = 0.01;
  options.missing_probability = 0.1;
  options.missing_as_nan = true;
  const StatusOr<ScanSimulation> noisy = SimulateScans(options);
  ASSERT_TRUE(clean.ok() && noisy.ok());
  EXPECT_NEAR(clean->scans[0].angle_increment_rad, 1.5 * M_PI / 1080, 1e-15);
  double sum2 = 0.0;
  int kept = 0, dropped = 0;
  for (size_t k = 0; k < clean->scans.size(); ++k) {
    for (int i = 0; i < options.beams; ++i) {
      const float c = clean->scans[k].ranges_m[i];
      const float n = noisy->scans[k].ranges_m[i];
      if (!clean->scans[k].IsReturn(i) || c < 0.5f || c > 14.5f) continue;
      if (std::isnan(n)) {
        ++dropped;
      } else {
        ++kept;
        sum2 += (n - c) * (n - c);
      }
    }
  }
  const double fraction = static_cast<double>(dropped) / (dropped + kept);
  EXPECT_NEAR(fraction, 0.1, 0.01);
  EXPECT_NEAR(std::sqrt(sum2 / kept), 0.01, 0.0003);  // ~30000 beams: 0.4 % standard error.
}

TEST(ScanSimulatorTest, InstantaneousScansAndLoggedStamps) {
  ScanSimOptions options = MovingOptions();
  options.sweep_s = 0.0;
  LoggingModel model;
  model.sensor_period_s = 0.1;
  model.pickup_latency_s = 0.03;
  options.logging = model;
  const StatusOr<ScanSimulation> sim = SimulateScans(options);
  ASSERT_TRUE(sim.ok()) << sim.status().message();
  ASSERT_FALSE(sim->scans.empty());
  for (size_t k = 0; k < sim->scans.size(); ++k) {
    const LaserScan& scan = sim->scans[k];
    EXPECT_EQ(scan.time_increment_s, 0.0);
    EXPECT_NEAR(scan.stamp_s - sim->truth.sweep_start_s[k], 0.03, 1e-9);
    const Pose2d& sensor = sim->truth.world_T_sensor[k];
    for (int i = 0; i < options.beams; ++i) {
      if (!scan.IsReturn(i)) continue;
      const double a = sensor(2) + scan.BeamAngle(i);
      EXPECT_LT(sim->world.DistanceTo(sensor.head<2>() +
                                      scan.ranges_m[i] * Eigen::Vector2d(std::cos(a), std::sin(a))),
                1e-6);
    }
  }
}

// A logger faster than the sensor picks a sample up twice: the second row holds the same scan, bit
// for bit, under its later stamp (as a real logger's repeat does).
TEST(ScanSimulatorTest, AHeldSampleIsWrittenAgainAsItWas) {
  ScanSimOptions options = MovingOptions();
  options.range_noise_sigma_m = 0.01;
  LoggingModel model;
  model.sensor_period_s = 0.1;
  model.logger_period_s = 0.07;
  options.logging = model;
  const StatusOr<ScanSimulation> sim = SimulateScans(options);
  ASSERT_TRUE(sim.ok()) << sim.status().message();
  int held = 0;
  for (size_t k = 1; k < sim->scans.size(); ++k) {
    if (sim->truth.sweep_start_s[k] != sim->truth.sweep_start_s[k - 1]) continue;
    ++held;
    EXPECT_GT(sim->scans[k].stamp_s, sim->scans[k - 1].stamp_s);
    EXPECT_EQ(sim->scans[k].ranges_m, sim->scans[k - 1].ranges_m);
  }
  EXPECT_GT(held, 5);
}

TEST(ScanSimulatorTest, BadOptionsAreErrors) {
  ScanSimOptions options = MovingOptions();
  options.beams = 0;
  EXPECT_NE(SimulateScans(options).status().message().find("beams"), std::string::npos);
  options = MovingOptions();
  options.range_max_m = 0.01;
  EXPECT_NE(SimulateScans(options).status().message().find("range_max_m"), std::string::npos);
  options = MovingOptions();
  options.missing_probability = 2.0;
  EXPECT_NE(SimulateScans(options).status().message().find("missing_probability"),
            std::string::npos);
  options = MovingOptions();
  options.laser.num_intervals = 0;
  EXPECT_NE(SimulateScans(options).status().message().find("num_intervals"), std::string::npos);
  options = MovingOptions();
  options.sweep_s = NAN;
  EXPECT_NE(SimulateScans(options).status().message().find("sweep_s"), std::string::npos);
}

TEST(ScanSimulatorTest, RobotMessagesJsonHoldsTheTopicsAndCounts) {
  ScanSimOptions options = MovingOptions();
  options.laser.num_intervals = 5;
  options.beams = 90;
  options.encoder_rate_hz = 50.0;
  options.missing_probability = 0.2;
  const StatusOr<ScanSimulation> sim = SimulateScans(options);
  ASSERT_TRUE(sim.ok());
  const RobotMessages messages = ScanSimulationMessages(*sim);
  const nlohmann::json json = nlohmann::json::parse(RobotMessagesJson(messages));
  std::map<std::string, std::string> types;
  for (const auto& topic : json.at("topics")) types[topic.at("name")] = topic.at("type");
  const std::map<std::string, std::string> expected = {{"/scan", "sensor_msgs/LaserScan"},
                                                       {"/joint_states", "sensor_msgs/JointState"},
                                                       {"/odom", "nav_msgs/Odometry"},
                                                       {"/tf_static", "tf2_msgs/TFMessage"}};
  EXPECT_EQ(types, expected);
  std::map<std::string, int> counts;
  int64_t previous = 0;
  int infinities = 0;
  for (const auto& message : json.at("messages")) {
    ++counts[message.at("topic")];
    const int64_t log_time = message.at("log_time_ns");
    EXPECT_GE(log_time, previous);
    previous = log_time;
    if (message.at("topic") == "/scan") {
      const auto& msg = message.at("msg");
      EXPECT_EQ(msg.at("ranges").size(), 90u);
      for (const auto& r : msg.at("ranges")) infinities += r.is_string() && r == "inf";
      EXPECT_EQ(msg.at("header").at("frame_id"), "laser");
      EXPECT_LT(msg.at("header").at("stamp").at("nanosec").get<int64_t>(), 1000000000);
    }
  }
  EXPECT_EQ(counts["/scan"], 6);
  EXPECT_EQ(counts["/joint_states"], static_cast<int>(sim->encoders.size()));
  EXPECT_EQ(counts["/odom"], static_cast<int>(sim->encoders.size()));
  EXPECT_EQ(counts["/tf_static"], 1);
  EXPECT_GT(infinities, 6 * 90 / 10);
  const auto& first_scan = *std::find_if(json.at("messages").begin(), json.at("messages").end(),
                                         [](const auto& m) { return m.at("topic") == "/scan"; });
  const double stamp =
      first_scan.at("msg").at("header").at("stamp").at("sec").get<int64_t>() +
      1e-9 * first_scan.at("msg").at("header").at("stamp").at("nanosec").get<int64_t>();
  EXPECT_NEAR(stamp, 1.7e9 + sim->scans[0].stamp_s, 1e-6);
  const auto& tf = *std::find_if(json.at("messages").begin(), json.at("messages").end(),
                                 [](const auto& m) { return m.at("topic") == "/tf_static"; });
  ASSERT_EQ(tf.at("msg").at("transforms").size(), 1u);
  const auto& mount = tf.at("msg").at("transforms")[0];
  EXPECT_EQ(mount.at("header").at("frame_id"), "base_link");
  EXPECT_EQ(mount.at("child_frame_id"), "laser");
  EXPECT_EQ(mount.at("transform").at("translation").at("x").get<double>(),
            sim->truth.base_T_sensor(0));
}

// Run with --gtest_also_run_disabled_tests for the figure.
TEST(ScanSimulatorTest, DISABLED_ThousandScansOf1081Beams) {
  ScanSimOptions options;
  options.laser.num_intervals = 999;
  options.beams = 1081;
  options.field_of_view_rad = 1.5 * M_PI;
  options.sweep_s = 0.025;
  options.range_noise_sigma_m = 0.01;
  options.world.kind = WorldKind::kMixed;
  options.world.clutter_per_m2 = 2.0;
  const auto start = std::chrono::steady_clock::now();
  const StatusOr<ScanSimulation> sim = SimulateScans(options);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(sim.ok());
  std::printf("1000 scans of 1081 beams, %zu segments: %.3f s\n", sim->world.segments().size(),
              seconds);
}

}  // namespace
}  // namespace calib
