// `calib calibrate` on a robot's bag, as a user runs it: bags written by the reference
// implementations from a simulated lidar robot (data/bags/README.md), and bad bags.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "tests/tools/cli_runner.h"

namespace {

namespace fs = std::filesystem;

using ::calib::testing::CliRun;
using ::calib::testing::ReadFile;

const fs::path kBags = fs::path(CALIB_SOURCE_DIR) / "data" / "bags";

// Every parameter of calibrate's JSON within 3σ of the truth's "estimate".
void ExpectWithinThreeSigma(const nlohmann::json& json, const nlohmann::json& truth) {
  for (const auto& [name, value] : truth.items()) {
    EXPECT_LT(std::abs(json["estimate"][name].get<double>() - value.get<double>()),
              3.0 * json["stddev"][name].get<double>())
        << name;
  }
}

class BagCliTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = ::calib::testing::MakeScratchDir("bag_cli_test_"); }
  void TearDown() override { fs::remove_all(dir_); }

  CliRun Calibrate(const fs::path& input, const std::string& flags = "") {
    return ::calib::testing::RunCalib("calibrate --quiet --input " + input.string() + " --output " +
                                          (dir_ / "out.json").string() + " " + flags,
                                      dir_);
  }

  void ExpectFailure(const fs::path& input, const std::string& flags,
                     const std::vector<std::string>& needles) {
    const CliRun run = Calibrate(input, flags);
    EXPECT_GT(run.exit_code, 0) << input << " " << flags;
    EXPECT_LT(run.exit_code, 128) << "crashed: " << input << " " << flags;
    for (const std::string& needle : needles) {
      EXPECT_NE(run.err.find(needle), std::string::npos) << "stderr lacks '" << needle << "':\n"
                                                         << run.err;
    }
  }

  // A directory of scans.csv and odometry.csv as `calib simulate --beams` writes it (beams at
  // their own times over a 0.1 s sweep), and its truth.
  void SimulateScansLog(const fs::path& log, const fs::path& truth) {
    const CliRun simulated = ::calib::testing::RunCalib(
        "simulate --beams 180 --intervals 400 --seed 11 --sweep 0.1 --output " + log.string() +
            " --truth " + truth.string(),
        dir_);
    ASSERT_EQ(simulated.exit_code, 0) << simulated.err;
  }

  fs::path dir_;
};

// Every parameter within 3σ of the simulator's truth, from the ROS 2 bag (zstd chunks, written
// by @mcap/core), a bag directory holding it, and the ROS 1 bag (lz4 chunks, python3-rosbag).
TEST_F(BagCliTest, BagsOfTheReferenceWritersCalibrateWithinThreeSigma) {
  const nlohmann::json truth =
      nlohmann::json::parse(ReadFile(kBags / "sim_robot_truth.json"))["estimate"];
  const fs::path directory = dir_ / "rosbag2_run";
  fs::create_directories(directory);
  fs::copy_file(kBags / "sim_robot_zstd.mcap", directory / "run_0.mcap");
  std::ofstream(directory / "metadata.yaml") << "rosbag2_bagfile_information:\n  version: 5\n";
  for (const fs::path& bag :
       {kBags / "sim_robot_zstd.mcap", directory, kBags / "sim_robot_lz4.bag"}) {
    SCOPED_TRACE(bag.string());
    const CliRun run = Calibrate(bag);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const nlohmann::json json = nlohmann::json::parse(ReadFile(dir_ / "out.json"));
    ExpectWithinThreeSigma(json, truth);
    const nlohmann::json& recording = json["recording"];
    EXPECT_EQ(recording["scan_topic"], "/scan");
    EXPECT_EQ(recording["scan_matching"]["failed"], 0);
    EXPECT_GE(recording["scan_matching"]["passes"], 2);  // The sweeps are de-skewed.
    EXPECT_LT(std::abs(recording["mounting_minus_nominal"]["sensor_x"].get<double>()), 0.01);
    EXPECT_EQ(json["timing"]["latent_times"]["sensor_clock"], "free_running");
  }
}

// The same robot with its wheels as raw encoder counts in the robot's own message, read through
// the definition the bag stores (or calib's own for a known type when rosbag2's Humble sqlite3
// stores none): TurtleBot3's counts in an MCAP and a ROS 1 bag, Kobuki's wrapping 16-bit ones in
// .db3 bags. Every parameter within 3σ; the wraps are named; a topic that is not there is.
TEST_F(BagCliTest, RawEncoderCountsOfTheRobotsOwnMessageCalibrateWithinThreeSigma) {
  const nlohmann::json truth =
      nlohmann::json::parse(ReadFile(kBags / "sim_robot_truth.json"))["estimate"];
  for (const char* name : {"sim_turtlebot_ticks_zstd.mcap", "sim_turtlebot_ticks_lz4.bag",
                           "sim_kobuki_ticks_db3", "sim_kobuki_ticks_humble_db3"}) {
    SCOPED_TRACE(name);
    const CliRun run = Calibrate(kBags / name);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const nlohmann::json json = nlohmann::json::parse(ReadFile(dir_ / "out.json"));
    ExpectWithinThreeSigma(json, truth);
    const std::string wheels = json["recording"]["wheel_angles"];
    EXPECT_NE(wheels.find("(left_encoder, right_encoder: "), std::string::npos) << wheels;
    const bool kobuki = std::string(name).find("kobuki") != std::string::npos;
    EXPECT_EQ(kobuki, json["warnings"].dump().find("wrapped") != std::string::npos)
        << json["warnings"];
  }
  const fs::path bag = kBags / "sim_turtlebot_ticks_zstd.mcap";
  ExpectFailure(bag, "--encoder_topic /wheel_ticks", {"no topic '/wheel_ticks'", "/sensor_state"});
  ExpectFailure(bag, "--encoder_topic /sensor_state --left_encoder_field left_ticks",
                {"no field 'left_ticks'", "left_encoder"});
}

// The same robot with its lidar upside down (tf_static rolls the laser frame by π), written by
// @mcap/core: its scans are mirrored and still de-skewed, every parameter within 3σ, and the
// summary says what was done.
TEST_F(BagCliTest, AnUpsideDownLidarsBagCalibratesWithinThreeSigma) {
  const nlohmann::json truth =
      nlohmann::json::parse(ReadFile(kBags / "sim_robot_upside_down_truth.json"))["estimate"];
  const CliRun run = Calibrate(kBags / "sim_robot_upside_down_zstd.mcap");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json json = nlohmann::json::parse(ReadFile(dir_ / "out.json"));
  ExpectWithinThreeSigma(json, truth);
  EXPECT_GE(json["recording"]["scan_matching"]["passes"], 2);  // The sweeps are de-skewed.
  EXPECT_LT(std::abs(json["recording"]["mounting_minus_nominal"]["sensor_x"].get<double>()), 0.01);
  EXPECT_NE(json["warnings"].dump().find("upside down"), std::string::npos) << json["warnings"];
}

// A bag rosbag2 split into three files, and the same recording in its sqlite3 storage (two files,
// each message zstd-compressed, Humble's schema), calibrate exactly as the one MCAP file does.
TEST_F(BagCliTest, ASplitBagCalibratesAsTheWholeOne) {
  nlohmann::json estimates[3];
  int k = 0;
  for (const fs::path& bag :
       {kBags / "sim_robot_split", kBags / "sim_robot_db3", kBags / "sim_robot_zstd.mcap"}) {
    const CliRun run = Calibrate(bag);
    ASSERT_EQ(run.exit_code, 0) << run.err;
    estimates[k++] = nlohmann::json::parse(ReadFile(dir_ / "out.json"))["estimate"];
  }
  EXPECT_EQ(estimates[0], estimates[2]);
  EXPECT_EQ(estimates[1], estimates[2]);
}

// --scan_points: the estimate refined against the scan points is the result, within 3σ of the
// truth with smaller σ than the two-stage route's, which the JSON keeps beside it.
TEST_F(BagCliTest, RefinedOnTheScanPointsWithinThreeSigma) {
  const nlohmann::json truth =
      nlohmann::json::parse(ReadFile(kBags / "sim_robot_truth.json"))["estimate"];
  for (const fs::path& bag : {kBags / "sim_robot_zstd.mcap", kBags / "sim_robot_lz4.bag"}) {
    SCOPED_TRACE(bag.string());
    const CliRun run = Calibrate(bag, "--scan_points");
    ASSERT_EQ(run.exit_code, 0) << run.err;
    const nlohmann::json json = nlohmann::json::parse(ReadFile(dir_ / "out.json"));
    const nlohmann::json& refined = json["scan_points"];
    ASSERT_TRUE(refined["refined"].get<bool>()) << refined.dump();
    EXPECT_TRUE(refined["converged"].get<bool>());
    EXPECT_GT(refined["pairs"].get<int>(), 300);
    for (const auto& [name, value] : truth.items()) {
      EXPECT_EQ(json["estimate"][name], refined["estimate"][name]) << name;
      EXPECT_LT(std::abs(json["estimate"][name].get<double>() - value.get<double>()),
                3.0 * json["stddev"][name].get<double>())
          << name;
      EXPECT_LT(refined["stddev"][name].get<double>(),
                refined["two_stage_stddev"][name].get<double>())
          << name;
    }
  }
}

// Logs from anything that is not a bag: a directory of scans.csv and odometry.csv, as `calib
// simulate --beams` writes it (beams at their own times over a 0.1 s sweep).
TEST_F(BagCliTest, AScansCsvDirectoryCalibratesWithinThreeSigma) {
  const fs::path log = dir_ / "scans_log", truth_path = dir_ / "truth.json";
  ASSERT_NO_FATAL_FAILURE(SimulateScansLog(log, truth_path));
  ASSERT_TRUE(fs::exists(log / "scans.csv"));
  const CliRun run = Calibrate(log);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json json = nlohmann::json::parse(ReadFile(dir_ / "out.json"));
  const nlohmann::json truth = nlohmann::json::parse(ReadFile(truth_path))["estimate"];
  ExpectWithinThreeSigma(json, truth);
  EXPECT_EQ(json["recording"]["scan_topic"], "scans.csv");
  EXPECT_EQ(json["verdict"], "trusted") << json["warnings"];
  // A scans.csv cut short inside its third line (a range missing) is named.
  std::string text = ReadFile(log / "scans.csv");
  const size_t third_line = text.find('\n', text.find('\n') + 1) + 1;
  text.erase(text.rfind(',', text.find('\n', third_line)));
  std::ofstream(log / "scans.csv") << text;
  ExpectFailure(log, "", {"scans.csv:3"});
}

// The raw format of Censi et al.'s recordings (a CSM laser log with the wheels' encoder counts,
// one per experiment, bzip2-compressed in a directory per experiment): `calib simulate` writes
// one, and a directory of two calibrates as one recording within 3σ, with the robot's body in
// the lidar's view left out. A truncated log is named by record.
TEST_F(BagCliTest, CsmLogsOfExperimentsCalibrateWithinThreeSigma) {
  const fs::path archive = dir_ / "l90";
  const fs::path truth_path = dir_ / "truth.json";
  for (const int seed : {21, 22}) {
    fs::create_directories(archive / ("exp" + std::to_string(seed)));
    const fs::path log = archive / ("exp" + std::to_string(seed)) / "log.log";
    const CliRun simulated = ::calib::testing::RunCalib(
        "simulate --beams 360 --intervals 300 --seed " + std::to_string(seed) +
            " --self_returns --output " + log.string() + " --truth " + truth_path.string(),
        dir_);
    ASSERT_EQ(simulated.exit_code, 0) << simulated.err;
  }
  const CliRun run = Calibrate(archive);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json json = nlohmann::json::parse(ReadFile(dir_ / "out.json"));
  ExpectWithinThreeSigma(json, nlohmann::json::parse(ReadFile(truth_path))["estimate"]);
  EXPECT_EQ(json["recording"]["scan_matching"]["segments"], 2);
  const std::string notes = json["recording"]["notes"].dump();
  EXPECT_NE(notes.find("2 logs joined"), std::string::npos) << notes;
  EXPECT_NE(notes.find("the robot's own body, left out"), std::string::npos) << notes;
  EXPECT_NE(json["recording"]["wheel_angles"].get<std::string>().find("2764.8 counts a turn"),
            std::string::npos);

  // Kept, the body's beams are matched; nearer than --lidar_min_range they are no returns.
  const CliRun near = Calibrate(archive, "--lidar_self_returns keep --lidar_min_range 0.3");
  ASSERT_EQ(near.exit_code, 0) << near.err;
  const nlohmann::json without = nlohmann::json::parse(ReadFile(dir_ / "out.json"));
  EXPECT_EQ(without["recording"]["notes"].dump().find("own body"), std::string::npos);
  ExpectWithinThreeSigma(without, nlohmann::json::parse(ReadFile(truth_path))["estimate"]);
  ExpectFailure(archive, "--lidar_self_returns drop", {"--lidar_self_returns drop: mask"});

  const fs::path cut = dir_ / "cut.log";
  const std::string text = ReadFile(archive / "exp21" / "log.log");
  std::ofstream(cut) << text.substr(0, text.find('\n', text.find('\n') + 1) + 200);
  ExpectFailure(cut, "", {"cut.log record 2 (line 3): the file ends inside the record"});
  // A corrupt bzip2 file, and a log named beside one that is not there.
  std::ofstream(dir_ / "bad.log.bz2") << "BZh91AY&SYgarbage";
  ExpectFailure(dir_ / "bad.log.bz2", "", {"bad.log.bz2: bz2 data end before their stream does"});
  ExpectFailure((archive / "exp21" / "log.log").string() + "," + (dir_ / "gone.log").string(), "",
                {"gone.log: no such file"});
}

// A driver that leaves time_increment 0 on a lidar that sweeps. Trusted (--lidar_beam_timing
// driver), calibrate warns (b was 4.9σ off on this log, the verdict "check"), and
// --lidar_rotation_period gives the beams their times back. Checked (the default), the sweeps'
// seams show one turn per scan period: a warning says so, and the calibration is right.
TEST_F(BagCliTest, ScansWithoutBeamTimesGetThemFromTheRotationPeriod) {
  const fs::path log = dir_ / "scans_log", truth_path = dir_ / "truth.json";
  ASSERT_NO_FATAL_FAILURE(SimulateScansLog(log, truth_path));
  const nlohmann::json truth = nlohmann::json::parse(ReadFile(truth_path))["estimate"];
  std::istringstream in(ReadFile(log / "scans.csv"));
  std::string line, text;
  for (int row = 0; std::getline(in, line); ++row) {
    if (row > 0) {  // t,angle_min,angle_increment,time_increment,...: the fourth field to 0.
      size_t at = 0;
      for (int comma = 0; comma < 3; ++comma) at = line.find(',', at) + 1;
      line.replace(at, line.find(',', at) - at, "0");
    }
    text += line + "\n";
  }
  std::ofstream(log / "scans.csv") << text;
  const std::string instant = "every scan's time_increment is 0";
  CliRun run = Calibrate(log, "--lidar_beam_timing driver");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  nlohmann::json json = nlohmann::json::parse(ReadFile(dir_ / "out.json"));
  EXPECT_NE(json["warnings"].dump().find(instant), std::string::npos) << json["warnings"];
  EXPECT_NE(json["verdict"], "trusted");
  EXPECT_FALSE(json["recording"].contains("beam_timing")) << json["recording"];

  run = Calibrate(log);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  json = nlohmann::json::parse(ReadFile(dir_ / "out.json"));
  EXPECT_EQ(json["warnings"].dump().find(instant), std::string::npos) << json["warnings"];
  EXPECT_NE(json["warnings"].dump().find("the beams' timing is not what the driver says"),
            std::string::npos)
      << json["warnings"];
  const nlohmann::json& checked = json["recording"]["beam_timing"];
  EXPECT_EQ(checked["changed"], true) << checked;
  EXPECT_NE(checked["used"].get<std::string>().find("in listed order"), std::string::npos)
      << checked;
  ExpectWithinThreeSigma(json, truth);

  run = Calibrate(log, "--lidar_rotation_period 0.1");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  json = nlohmann::json::parse(ReadFile(dir_ / "out.json"));
  ExpectWithinThreeSigma(json, truth);
  EXPECT_EQ(json["verdict"], "trusted") << json["warnings"];
  EXPECT_EQ(json["recording"]["beam_timing"]["changed"], false) << json["recording"];
  ExpectFailure(log, "--lidar_rotation_period -0.1", {"--lidar_rotation_period -0.1", "one turn"});
  ExpectFailure(log, "--lidar_beam_timing sometimes", {"--lidar_beam_timing sometimes", "auto"});
}

// `calib diagnose` on raw scans: the scans are matched and timed as calibrate does, then
// searched. A left wheel 1 % larger after 30 s is found and adopted; the clean reference bag
// adopts nothing.
TEST_F(BagCliTest, DiagnoseFindsARadiusChangeInRawScans) {
  const fs::path log = dir_ / "radius_change";
  const CliRun simulated = ::calib::testing::RunCalib(
      "simulate --beams 180 --intervals 600 --seed 4 --sweep 0.1 --radius_change_time 30 "
      "--r_l_after 0.101 --r_r_after 0.1 --output " +
          log.string() + " --truth " + (dir_ / "truth.json").string(),
      dir_);
  ASSERT_EQ(simulated.exit_code, 0) << simulated.err;
  const auto diagnose = [&](const fs::path& input) {
    const CliRun run = ::calib::testing::RunCalib(
        "diagnose --quiet --input " + input.string() + " --output " + (dir_ / "d.json").string(),
        dir_);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return nlohmann::json::parse(ReadFile(dir_ / "d.json"));
  };
  const nlohmann::json changed = diagnose(log);
  EXPECT_EQ(changed["adopted"], nlohmann::json::array({"wheel_radius_change"}))
      << changed["adopted"];
  EXPECT_EQ(changed["timing"]["treatment"], "latent_times");
  // The clean bag's scanner is stamped 20 ms late (data/bags/README.md). The latent times place
  // it at about −17 ms; a residual time offset of about −2 ms on top is a true finding (since the
  // sweeps are de-skewed through every encoder step it is significant), nothing else is.
  const nlohmann::json clean = diagnose(kBags / "sim_robot_zstd.mcap");
  for (const auto& effect : clean["adopted"]) EXPECT_EQ(effect, "time_offset") << clean["adopted"];
  if (!clean["adopted"].empty()) {
    const double latent_s = clean["timing"]["latent_times"]["time_offset_s"];
    const double residual_s = clean["final"]["effect_values"]["time_offset"]["value"];
    EXPECT_LT(std::abs(latent_s + residual_s + 0.020), std::abs(latent_s + 0.020));
  }
}

TEST_F(BagCliTest, BadBagsAndTopicsAreNamed) {
  const fs::path bag = kBags / "sim_robot_lz4.bag";
  ExpectFailure(bag, "--scan_topic /front_scan", {"'/front_scan'", "/scan (sensor_msgs/LaserScan"});
  ExpectFailure(bag, "--left_wheel_joint wheel_l --right_wheel_joint wheel_r",
                {"'wheel_l'", "left_wheel_joint"});
  ExpectFailure(bag, "--odom_topic /odom", {"--nominal_wheel_radius"});
  ExpectFailure(bag, "--wheel_angle_unit furlongs", {"--wheel_angle_unit furlongs", "ticks:N"});
  ExpectFailure(bag, "--wheel_angle_unit ticks:0", {"--wheel_angle_unit ticks:0"});
  ExpectFailure(bag, "--ticks_per_rev 4096 --wheel_angle_unit deg",
                {"--ticks_per_rev and --wheel_angle_unit deg", "give one"});
  ExpectFailure(bag, "--ticks_per_rev -2", {"--ticks_per_rev must be positive"});
  // Bags separated by commas are one robot's recording (a bag split in parts, a session's runs);
  // the same run given twice, here in two formats, is refused.
  ExpectFailure(bag.string() + "," + (kBags / "sim_robot_zstd.mcap").string(), "",
                {"hold the same scans: one recording given twice?"});
  std::ofstream(dir_ / "empty.mcap").flush();
  ExpectFailure(dir_ / "empty.mcap", "", {"empty.mcap: not a bag: the file is empty"});
  for (const fs::path& source : {bag, kBags / "sim_robot_zstd.mcap"}) {
    const std::string bytes = ReadFile(source);
    const fs::path cut = dir_ / ("cut" + source.extension().string());
    std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    ExpectFailure(cut, "", {cut.string(), "truncated"});
  }
  std::ofstream(dir_ / "empty.db3").flush();
  ExpectFailure(dir_ / "empty.db3", "", {"empty.db3: not a bag: the file is empty"});
  const std::string db3 = ReadFile(kBags / "sim_robot_db3" / "sim_robot_db3_0.db3");
  const fs::path cut = dir_ / "cut.db3";
  std::ofstream(cut, std::ios::binary) << db3.substr(0, db3.size() / 2);
  ExpectFailure(cut, "", {cut.string(), "truncated or corrupt"});
}

}  // namespace
