// The command line's ways out: a summary-only run, JSON on stdout, the deployable exports, and a
// known sensor latency applied with --time_offset.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/tools/cli_runner.h"

namespace {

namespace fs = std::filesystem;

using ::calib::testing::CliRun;
using ::calib::testing::ReadFile;

const fs::path kData = fs::path(CALIB_SOURCE_DIR) / "data";

class DeployCliTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = ::calib::testing::MakeScratchDir("calib_deploy_cli_"); }
  void TearDown() override { fs::remove_all(dir_); }

  // Run from inside the scratch folder, so that files written "in the working directory" land
  // there.
  CliRun Calib(const std::string& args) { return ::calib::testing::RunCalib(args, dir_, dir_); }

  // The value after "key: " in a YAML text.
  static double Yaml(const std::string& yaml, const std::string& key) {
    const size_t at = yaml.find("\n" + key + ": ");
    EXPECT_NE(at, std::string::npos) << key << " in\n" << yaml;
    return at == std::string::npos ? NAN : std::stod(yaml.substr(at + key.size() + 3));
  }

  // (estimate − truth)/σ of every parameter of a calibrate JSON.
  static std::vector<double> Z(const nlohmann::json& json, const nlohmann::json& truth) {
    std::vector<double> z;
    for (const auto& [name, value] : truth["estimate"].items()) {
      z.push_back((json["estimate"][name].get<double>() - value.get<double>()) /
                  json["stddev"][name].get<double>());
    }
    return z;
  }

  fs::path dir_;
};

TEST_F(DeployCliTest, WithoutOutputOnlyTheSummaryIsPrinted) {
  const CliRun run = Calib("calibrate --input " + (kData / "sample_laser.tuple").string());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("verdict: trusted"), std::string::npos) << run.out;
  for (const auto& entry : fs::directory_iterator(dir_)) {
    const std::string name = entry.path().filename().string();
    EXPECT_TRUE(name == "stdout.txt" || name == "stderr.txt") << "wrote " << name;
  }
}

TEST_F(DeployCliTest, DashWritesTheJsonOnStdoutAndTheSummaryOnStderr) {
  const CliRun run =
      Calib("calibrate --input " + (kData / "sample_laser.tuple").string() + " --output -");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json json = nlohmann::json::parse(run.out);
  EXPECT_EQ(json["problem"], "laser");
  EXPECT_TRUE(json["estimate"].contains("r_l"));
  EXPECT_GT(json["odometry_drift"]["calibrated_1sigma"]["turn_deg_per_turn"].get<double>(), 0.0);
  EXPECT_NE(run.err.find("verdict:"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(dir_ / "-"));
  const CliRun diagnose = Calib("diagnose --quiet --output - --input " +
                                (kData / "diagnose" / "time_offset.tuple").string());
  ASSERT_EQ(diagnose.exit_code, 0) << diagnose.err;
  EXPECT_TRUE(nlohmann::json::parse(diagnose.out).contains("findings"));
  EXPECT_FALSE(fs::exists(dir_ / "-_plots"));
}

// The exports agree with the JSON beside them: diff_drive_controller's radius × multiplier gives
// each wheel, the static transform and the URDF joint the calibrated mounting.
TEST_F(DeployCliTest, ExportsBesideTheJsonAgreeWithIt) {
  const fs::path out = dir_ / "robot.json";
  const CliRun run = Calib("calibrate --input " + (kData / "sample_laser.tuple").string() +
                           " --output " + out.string() + " --export all");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const nlohmann::json json = nlohmann::json::parse(ReadFile(out));
  const nlohmann::json& e = json["estimate"];
  ASSERT_EQ(json["exports"].size(), 3u);
  EXPECT_NE(run.out.find("deploy: " + (dir_ / "robot.yaml").string()), std::string::npos);
  const std::string yaml = ReadFile(dir_ / "robot.yaml");
  const double r = Yaml(yaml, "wheel_radius");
  EXPECT_NEAR(r, 0.5 * (e["r_l"].get<double>() + e["r_r"].get<double>()), 1e-6);
  EXPECT_NEAR(Yaml(yaml, "wheel_separation"), e["b"].get<double>(), 1e-6);
  EXPECT_NEAR(Yaml(yaml, "    left_wheel_radius_multiplier") * r, e["r_l"].get<double>(), 1e-6);
  EXPECT_NEAR(Yaml(yaml, "    right_wheel_radius_multiplier") * r, e["r_r"].get<double>(), 1e-6);
  EXPECT_NEAR(Yaml(yaml, "  x"), e["sensor_x"].get<double>(), 1e-6);
  EXPECT_NEAR(Yaml(yaml, "  yaw"), e["sensor_theta"].get<double>(), 1e-6);
  std::istringstream tf(ReadFile(dir_ / "robot.tf"));
  double x, y, z, yaw, pitch, roll;
  std::string parent, child;
  ASSERT_TRUE(tf >> x >> y >> z >> yaw >> pitch >> roll >> parent >> child);
  EXPECT_NEAR(x, e["sensor_x"].get<double>(), 1e-6);
  EXPECT_NEAR(y, e["sensor_y"].get<double>(), 1e-6);
  EXPECT_NEAR(yaw, e["sensor_theta"].get<double>(), 1e-6);
  EXPECT_EQ(parent + " " + child, "base_link laser");
  EXPECT_NE(ReadFile(dir_ / "robot.urdf").find("<origin xyz="), std::string::npos);
}

TEST_F(DeployCliTest, WithoutOutputTheExportsGoToTheWorkingDirectory) {
  const CliRun run =
      Calib("calibrate --quiet --export yaml --input " + (kData / "sample_laser.tuple").string());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_TRUE(fs::exists(dir_ / "calib_calibration.yaml"));
  EXPECT_FALSE(fs::exists(dir_ / "calib_calibration.tf"));
}

// A bag's frames and tf height reach the exports, and the sensor's stamp offset the YAML.
TEST_F(DeployCliTest, BagExportsNameItsFramesAndTheStampOffset) {
  const CliRun run = Calib("calibrate --quiet --timing stamps --export yaml,tf --output " +
                           (dir_ / "bag.json").string() + " --input " +
                           (kData / "bags" / "sim_robot_zstd.mcap").string());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string yaml = ReadFile(dir_ / "bag.yaml");
  EXPECT_NE(yaml.find("# from tf"), std::string::npos) << yaml;
  const nlohmann::json json = nlohmann::json::parse(ReadFile(dir_ / "bag.json"));
  EXPECT_NEAR(Yaml(yaml, "sensor_time_offset"),
              json["timing"]["latent_times"]["time_offset_s"].get<double>(), 1e-6);
  EXPECT_NE(ReadFile(dir_ / "bag.tf").find(" base_link laser"), std::string::npos);
}

// The bearing result in robot terms: wheel radius × δR, δL, wheelbase × δB, the camera at
// (ρ cos φ, ρ sin φ) — each within 3σ of the sample's truth.
TEST_F(DeployCliTest, BearingExportsInRobotTermsWithinThreeSigma) {
  const CliRun run =
      Calib("calibrate --quiet --export yaml --output " + (dir_ / "b.json").string() + " --input " +
            (kData / "sample_bearing").string());
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string yaml = ReadFile(dir_ / "b.yaml");
  const nlohmann::json truth =
      nlohmann::json::parse(ReadFile(kData / "sample_bearing" / "truth.json"))["estimate"];
  const double r = 0.3, b = 0.5;  // meta.json's nominal wheels.
  const std::vector<std::pair<std::string, double>> expected = {
      {"left_wheel_radius", r * truth["delta_l"].get<double>()},
      {"right_wheel_radius", r * truth["delta_r"].get<double>()},
      {"wheel_separation", b * truth["delta_b"].get<double>()},
      {"  x", truth["rho"].get<double>()},
      {"  y", 0.0},
      {"  yaw", M_PI / 2}};
  for (const auto& [key, value] : expected) {
    const size_t at = yaml.find("\n" + key + ": ");
    ASSERT_NE(at, std::string::npos) << key;
    const std::string line = yaml.substr(at + 1, yaml.find('\n', at + 1) - at - 1);
    const double sigma = std::stod(line.substr(line.find("± ") + 3));
    EXPECT_LE(std::abs(Yaml(yaml, key) - value), 3.0 * sigma) << line;
  }
}

TEST_F(DeployCliTest, BearingExportWithoutADistanceSaysWhatIsMissing) {
  fs::copy(kData / "sample_bearing", dir_ / "log");
  std::ofstream(dir_ / "log" / "meta.json") << "{\"wheel_radius\": 0.3, \"wheelbase\": 0.5}\n";
  const CliRun run = Calib("calibrate --quiet --export yaml --input " + (dir_ / "log").string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("initial distance"), std::string::npos) << run.err;
  EXPECT_FALSE(fs::exists(dir_ / "calib_calibration.yaml"));
}

TEST_F(DeployCliTest, BadExportFormatIsRefusedFirst) {
  const CliRun run =
      Calib("calibrate --export yml --input " + (kData / "sample_laser.tuple").string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("unknown --export 'yml'"), std::string::npos) << run.err;
  EXPECT_EQ(run.out, "");
}

// Scans stamped 300 ms before they were taken: with the stamps taken as sample times the radii
// are 3σ off (the redescending passes reject the fastest intervals, so a smaller offset shows
// less); the same log with --time_offset 0.3 is within 2σ. A log of intervals has no stamps
// to move: a clear error.
TEST_F(DeployCliTest, TimeOffsetMovesTheSensorStamps) {
  const fs::path log = dir_ / "streams";
  ASSERT_EQ(Calib("simulate --quiet --intervals 700 --max_wheel_speed 8 --noise_xy 0.0005 "
                  "--noise_theta 0.0005 --time_offset 0.3 --output " +
                  log.string() + " --truth " + (dir_ / "truth.json").string())
                .exit_code,
            0);
  const nlohmann::json truth = nlohmann::json::parse(ReadFile(dir_ / "truth.json"));
  const std::string base = "calibrate --quiet --timing off --input " + log.string() + " --output -";
  const CliRun plain = Calib(base), shifted = Calib(base + " --time_offset 0.3");
  ASSERT_EQ(plain.exit_code, 0) << plain.err;
  ASSERT_EQ(shifted.exit_code, 0) << shifted.err;
  EXPECT_GT(Z(nlohmann::json::parse(plain.out), truth)[0], 2.5);
  for (double z : Z(nlohmann::json::parse(shifted.out), truth)) EXPECT_LT(std::abs(z), 2.0);
  const CliRun not_finite = Calib(base + " --time_offset nan");
  EXPECT_EQ(not_finite.exit_code, 1);
  EXPECT_NE(not_finite.err.find("--time_offset must be a finite number"), std::string::npos);
  const CliRun intervals =
      Calib("calibrate --time_offset 0.1 --input " + (kData / "sample_laser.tuple").string());
  EXPECT_EQ(intervals.exit_code, 1);
  EXPECT_NE(intervals.err.find("sample_laser.tuple: a time offset applies to sample stamps"),
            std::string::npos)
      << intervals.err;
}

// An output in a folder that does not exist is refused before any work, in every command, with
// the path named; nothing is created.
TEST_F(DeployCliTest, OutputInAMissingFolderIsRefused) {
  const std::string missing = (dir_ / "no" / "such").string();
  const std::string sample = (kData / "sample_laser.tuple").string();
  for (const std::string& command :
       {"calibrate --input " + sample + " --output " + missing + "/x.json",
        "diagnose --input " + sample + " --output " + missing + "/x.json",
        "simulate --output " + missing + "/x.tuple",
        "simulate --output " + (dir_ / "x.tuple").string() + " --truth " + missing + "/t.json",
        "calibrate --input " + sample + " --output " + dir_.string()}) {
    const CliRun run = Calib(command);
    EXPECT_EQ(run.exit_code, 1) << command;
    EXPECT_EQ(run.err.find("calib: error: --"), 0u) << run.err;
    EXPECT_FALSE(fs::exists(dir_ / "no")) << command;
  }
}

}  // namespace
