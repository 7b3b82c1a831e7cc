// `calib diagnose` as a user runs it on a laser log and on a bearing directory: the contract's
// JSON keys, the plots, and a clean failure on bad input (skips without the binary).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/tools/cli_runner.h"

namespace {

namespace fs = std::filesystem;

using ::calib::testing::CliRun;
using ::calib::testing::ReadFile;
using ::calib::testing::RunCalib;

const fs::path kDataDir = fs::path(CALIB_SOURCE_DIR) / "data" / "diagnose";

class DiagnoseCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const fs::path binary = fs::path(CALIB_BINARY_DIR) / "bin" / "calib";
    if (!fs::exists(binary)) GTEST_SKIP() << binary << " is not built";
    dir_ = ::calib::testing::MakeScratchDir("calib_diagnose_cli_test_");
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }

  // Diagnoses `input` into dir_/result.json; expects success and returns the JSON (empty on a
  // failure).
  nlohmann::json Diagnose(const fs::path& input) {
    const CliRun run = RunCalib("diagnose --quiet --input " + input.string() + " --output " +
                                    (dir_ / "result.json").string(),
                                dir_);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    if (run.exit_code != 0) return nlohmann::json::object();
    return nlohmann::json::parse(ReadFile(dir_ / "result.json"));
  }

  // Every finding carries the contract's keys.
  static void ExpectContractKeys(const nlohmann::json& finding) {
    for (const char* key : {"effect", "significant", "value", "stddev", "unit", "statement"}) {
      EXPECT_TRUE(finding.contains(key)) << key;
    }
  }

  fs::path dir_;
};

TEST_F(DiagnoseCliTest, LaserLogGivesTheContractJsonAndPlots) {
  const nlohmann::json json = Diagnose(kDataDir / "time_offset.tuple");
  ASSERT_TRUE(json.contains("baseline") && json.contains("findings") && json.contains("final"));
  EXPECT_TRUE(json["baseline"]["estimate"].contains("sensor_theta"));
  EXPECT_EQ(json["baseline"]["rms"].size(), 3u);
  EXPECT_EQ(json["final"]["effects"], nlohmann::json::array({"time_offset"}));
  bool found = false;
  for (const auto& f : json["findings"]) {
    ExpectContractKeys(f);
    if (f["effect"] == "time_offset") {
      found = true;
      EXPECT_TRUE(f["significant"].get<bool>());
      EXPECT_EQ(f["unit"], "s");
      ASSERT_TRUE(f.contains("plot"));
      EXPECT_TRUE(fs::exists(f["plot"].get<std::string>()));
    }
    if (f["effect"] == "icr_offset_x") {
      EXPECT_FALSE(f["significant"].get<bool>());
      EXPECT_EQ(f["confounded_with"], nlohmann::json::array({"sensor_x"}));
    }
  }
  EXPECT_TRUE(found);
  EXPECT_TRUE(fs::exists(dir_ / "result_plots" / "residuals_vs_time.svg"));
  // An unreadable log: a non-zero status.
  const CliRun bad = RunCalib("diagnose --quiet --input " + (dir_ / "missing.tuple").string() +
                                  " --output " + (dir_ / "x.json").string(),
                              dir_);
  EXPECT_NE(bad.exit_code, 0);
}

TEST_F(DiagnoseCliTest, BearingDirectoryGivesTheContractJsonAndPlots) {
  const fs::path input = kDataDir / "bearing_time_offset";
  const nlohmann::json json = Diagnose(input);
  ASSERT_TRUE(json.contains("baseline") && json.contains("findings") && json.contains("final"));
  EXPECT_EQ(json["problem"], "bearing");
  for (const char* name : {"phi", "psi", "eta", "delta", "xi", "rho", "delta_r"}) {
    EXPECT_TRUE(json["baseline"]["estimate"].contains(name)) << name;
    EXPECT_TRUE(json["final"]["estimate"].contains(name)) << name;
  }
  EXPECT_EQ(json["baseline"]["rms"].size(), 1u);
  EXPECT_EQ(json["final"]["effects"], nlohmann::json::array({"time_offset"}));
  ASSERT_EQ(json["findings"].size(), 1u);
  const nlohmann::json& f = json["findings"][0];
  ExpectContractKeys(f);
  EXPECT_EQ(f["effect"], "time_offset");
  EXPECT_TRUE(f["significant"].get<bool>());
  EXPECT_EQ(f["unit"], "s");
  ASSERT_TRUE(f.contains("plot"));
  EXPECT_TRUE(fs::exists(f["plot"].get<std::string>()));
  EXPECT_TRUE(fs::exists(dir_ / "result_plots" / "residuals_vs_time.svg"));
  // A directory with a broken bearings.csv: a message naming the file, a non-zero status.
  fs::create_directories(dir_ / "broken");
  for (const char* name : {"odometry.csv", "meta.json"}) {
    fs::copy_file(input / name, dir_ / "broken" / name);
  }
  std::ofstream(dir_ / "broken" / "bearings.csv") << "run,t,bearing\n1,0,nan\n";
  const CliRun bad = RunCalib("diagnose --quiet --input " + (dir_ / "broken").string() +
                                  " --output " + (dir_ / "x.json").string(),
                              dir_);
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("bearings.csv"), std::string::npos) << bad.err;
}

// Which single estimate to deploy: the final fit; after a radius change, the radii after it; a
// time offset the driver applies; slip named as what a standard controller cannot express.
TEST_F(DiagnoseCliTest, SaysWhatToDeploy) {
  nlohmann::json json = Diagnose(kDataDir / "wheel_radius_change.tuple");
  ASSERT_TRUE(json.contains("deploy"));
  const nlohmann::json* change = nullptr;
  for (const auto& f : json["findings"]) {
    if (f["effect"] == "wheel_radius_change") change = &f;
  }
  ASSERT_NE(change, nullptr);
  EXPECT_EQ(json["deploy"]["estimate"]["r_l"], (*change)["r_l_after"]);
  EXPECT_EQ(json["deploy"]["estimate"]["r_r"], (*change)["r_r_after"]);
  EXPECT_EQ(json["deploy"]["estimate"]["b"], json["final"]["estimate"]["b"]);

  json = Diagnose(kDataDir / "time_offset.tuple");
  EXPECT_NEAR(json["deploy"]["sensor_time_offset_s"].get<double>(),
              json["final"]["effect_values"]["time_offset"]["value"].get<double>(), 1e-12);
  EXPECT_TRUE(json["deploy"]["not_expressible"].empty());

  json = Diagnose(kDataDir / "lateral_slip.tuple");
  EXPECT_EQ(json["deploy"]["not_expressible"], nlohmann::json::array({"lateral_slip"}));
  EXPECT_EQ(json["deploy"]["estimate"], json["final"]["estimate"]);
}

}  // namespace
