// The common input mistakes as a user makes them: a correct simulated log (`calib simulate`)
// written with wheel ticks, θ in degrees or wrapped wheel angles. The tool says what is wrong and
// prints no number; --ticks_per_rev turns the ticks into the correct log's result.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "tests/tools/cli_runner.h"

namespace {

namespace fs = std::filesystem;

using ::calib::testing::CliRun;
using ::calib::testing::CsvColumn;
using ::calib::testing::ReadFile;
using ::calib::testing::RewriteCsv;

constexpr double kTicksPerRev = 4096.0;

class InputSanityCliTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = ::calib::testing::MakeScratchDir("input_sanity_cli_test_"); }
  void TearDown() override { fs::remove_all(dir_); }

  CliRun Calib(const std::string& args) { return ::calib::testing::RunCalib(args, dir_); }

  // `calib simulate` into `name` (a .csv file, or a stream directory without extension).
  fs::path Simulate(const std::string& name) {
    const fs::path path = dir_ / name;
    const std::string encoders = path.has_extension() ? "" : " --encoder_period 0.02";
    const CliRun run =
        Calib("simulate --intervals 300 --seed 3" + encoders + " --output " + path.string());
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return path;
  }

  // A copy of the stream directory `streams` named `name`, its wheel angles times `factor`.
  fs::path ScaledWheels(const fs::path& streams, const std::string& name, double factor) {
    const fs::path scaled = dir_ / name;
    fs::create_directories(scaled);
    fs::copy_file(streams / "sensor_poses.csv", scaled / "sensor_poses.csv");
    RewriteCsv(streams / "odometry.csv", scaled / "odometry.csv",
               [factor](const std::vector<std::string>&, std::vector<double>* row) {
                 (*row)[1] *= factor;
                 (*row)[2] *= factor;
               });
    return scaled;
  }

  std::string Calibrate(const fs::path& input, const std::string& extra = "") {
    fs::remove(dir_ / "out.json");
    return "calibrate --input " + input.string() + " --output " + (dir_ / "out.json").string() +
           " " + extra;
  }

  // A refusal: non-zero exit, every needle on stderr, no JSON and no parameter printed.
  void ExpectRefused(const CliRun& run, const std::vector<std::string>& needles) {
    EXPECT_EQ(run.exit_code, 1) << run.err;
    for (const std::string& needle : needles) {
      EXPECT_NE(run.err.find(needle), std::string::npos) << "lacks '" << needle << "':\n"
                                                         << run.err;
    }
    EXPECT_EQ(run.err.find("positive wheel speeds drive the robot forward"), std::string::npos)
        << run.err;
    EXPECT_EQ(run.out.find("r_l"), std::string::npos) << run.out;
    EXPECT_FALSE(fs::exists(dir_ / "out.json"));
  }

  nlohmann::json Result(const CliRun& run) {
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return nlohmann::json::parse(ReadFile(dir_ / "out.json"));
  }

  fs::path dir_;
};

TEST_F(InputSanityCliTest, TicksAreRefusedAndTicksPerRevGivesTheCorrectResult) {
  const fs::path good = Simulate("good.csv");
  const nlohmann::json expected = Result(Calib(Calibrate(good)));
  EXPECT_EQ(expected["verdict"], "trusted") << expected["warnings"];
  const fs::path ticks = dir_ / "ticks.csv";
  RewriteCsv(good, ticks, [](const std::vector<std::string>& header, std::vector<double>* row) {
    for (const char* wheel : {"phi_l", "phi_r"}) {
      (*row)[CsvColumn(header, wheel)] *= kTicksPerRev / (2.0 * M_PI);
    }
  });
  ExpectRefused(Calib(Calibrate(ticks)),
                {"ticks.csv: the wheel radius comes out at", "encoder ticks", "--ticks_per_rev N"});
  ExpectRefused(
      Calib("diagnose --input " + ticks.string() + " --output " + (dir_ / "out.json").string()),
      {"encoder ticks", "--ticks_per_rev N"});

  const nlohmann::json converted =
      Result(Calib(Calibrate(ticks, "--ticks_per_rev " + std::to_string(kTicksPerRev))));
  for (const char* param : {"r_l", "r_r", "b", "sensor_x", "sensor_y", "sensor_theta"}) {
    EXPECT_NEAR(converted["estimate"][param].get<double>(),
                expected["estimate"][param].get<double>(),
                1e-6 * std::abs(expected["estimate"][param].get<double>()))
        << param;
  }
  EXPECT_EQ(converted["verdict"], "trusted") << converted["warnings"];
  ExpectRefused(Calib(Calibrate(ticks, "--ticks_per_rev -1")), {"--ticks_per_rev"});
}

TEST_F(InputSanityCliTest, StreamTicksAreConvertedByTicksPerRev) {
  const fs::path good = Simulate("good_streams");
  const fs::path ticks = ScaledWheels(good, "ticks_streams", kTicksPerRev / (2.0 * M_PI));
  ExpectRefused(Calib(Calibrate(ticks, "--timing off")),
                {"the left and right columns of odometry.csv", "encoder ticks"});
  const nlohmann::json expected = Result(Calib(Calibrate(good, "--timing off")));
  const nlohmann::json converted = Result(
      Calib(Calibrate(ticks, "--timing off --ticks_per_rev " + std::to_string(kTicksPerRev))));
  EXPECT_NEAR(converted["estimate"]["r_l"].get<double>(), expected["estimate"]["r_l"].get<double>(),
              1e-8);
  EXPECT_NEAR(converted["estimate"]["b"].get<double>(), expected["estimate"]["b"].get<double>(),
              1e-8);
}

// --wheel_angle_unit is not for bags only: a stream directory and an interval log whose wheel
// readings are in degrees give the radians' result with it (it was once ignored off bags).
TEST_F(InputSanityCliTest, WheelAngleUnitConvertsStreamsAndIntervalLogs) {
  const fs::path good_streams = Simulate("good_streams");
  const fs::path degrees = ScaledWheels(good_streams, "degrees_streams", 180.0 / M_PI);
  const CliRun ignored = Calib(Calibrate(degrees, "--timing off"));
  EXPECT_EQ(ignored.exit_code, 1) << ignored.err;
  EXPECT_NE(ignored.err.find("--wheel_angle_unit deg"), std::string::npos) << ignored.err;
  const nlohmann::json expected = Result(Calib(Calibrate(good_streams, "--timing off")));
  const nlohmann::json converted =
      Result(Calib(Calibrate(degrees, "--timing off --wheel_angle_unit deg")));
  for (const char* param : {"r_l", "r_r", "b"}) {
    EXPECT_NEAR(converted["estimate"][param].get<double>(),
                expected["estimate"][param].get<double>(), 1e-8)
        << param;
  }

  const fs::path good = Simulate("good.csv");
  const fs::path degrees_csv = dir_ / "degrees.csv";
  RewriteCsv(good, degrees_csv,
             [](const std::vector<std::string>& header, std::vector<double>* row) {
               for (const char* wheel : {"phi_l", "phi_r"}) {
                 (*row)[CsvColumn(header, wheel)] *= 180.0 / M_PI;
               }
             });
  const nlohmann::json expected_csv = Result(Calib(Calibrate(good)));
  const nlohmann::json converted_csv =
      Result(Calib(Calibrate(degrees_csv, "--wheel_angle_unit deg")));
  EXPECT_NEAR(converted_csv["estimate"]["r_l"].get<double>(),
              expected_csv["estimate"]["r_l"].get<double>(), 1e-8);
  EXPECT_EQ(converted_csv["verdict"], "trusted") << converted_csv["warnings"];
  ExpectRefused(Calib(Calibrate(good, "--wheel_angle_unit furlongs")), {"--wheel_angle_unit"});
  // A unit given to readings already in radians: the refusal says the flag may be the mistake.
  ExpectRefused(Calib(Calibrate(good_streams, "--timing off --wheel_angle_unit deg")),
                {"converted with --wheel_angle_unit deg", "leave it out"});
  ExpectRefused(Calib(Calibrate(good, "--wheel_angle_unit deg --ticks_per_rev 4096")),
                {"--ticks_per_rev and --wheel_angle_unit deg"});
}

TEST_F(InputSanityCliTest, ThetaInDegreesIsRefused) {
  const fs::path good = Simulate("good.csv");
  const fs::path degrees = dir_ / "degrees.csv";
  RewriteCsv(good, degrees, [](const std::vector<std::string>& header, std::vector<double>* row) {
    (*row)[CsvColumn(header, "sm_theta")] *= 180.0 / M_PI;
  });
  ExpectRefused(Calib(Calibrate(degrees)), {"degrees.csv: sm_theta looks like degrees, not radians",
                                            "Convert sm_theta to radians"});
}

TEST_F(InputSanityCliTest, SwappedWheelsAreNamed) {
  const fs::path good = Simulate("good.csv");
  const fs::path swapped = dir_ / "swapped.csv";
  RewriteCsv(good, swapped, [](const std::vector<std::string>& header, std::vector<double>* row) {
    std::swap((*row)[CsvColumn(header, "phi_l")], (*row)[CsvColumn(header, "phi_r")]);
  });
  const CliRun run = Calib(Calibrate(swapped));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("phi_l and phi_r swapped"), std::string::npos) << run.err;
}

// Wrapped joint angles are unwrapped, and the warning reaches the summary, the JSON and the
// verdict; the numbers are the correct log's.
TEST_F(InputSanityCliTest, WrappedWheelAnglesAreUnwrappedWithAWarning) {
  const fs::path good = Simulate("good_streams");
  const fs::path wrapped = dir_ / "wrapped_streams";
  fs::create_directories(wrapped);
  fs::copy_file(good / "sensor_poses.csv", wrapped / "sensor_poses.csv");
  RewriteCsv(good / "odometry.csv", wrapped / "odometry.csv",
             [](const std::vector<std::string>&, std::vector<double>* row) {
               (*row)[1] = std::remainder((*row)[1], 2.0 * M_PI);
               (*row)[2] = std::remainder((*row)[2], 2.0 * M_PI);
             });
  const nlohmann::json expected = Result(Calib(Calibrate(good, "--timing off")));
  const CliRun run = Calib(Calibrate(wrapped, "--timing off"));
  const nlohmann::json result = Result(run);
  EXPECT_NEAR(result["estimate"]["r_l"].get<double>(), expected["estimate"]["r_l"].get<double>(),
              1e-9);
  EXPECT_NE(run.out.find("jumps of 2π were unwrapped"), std::string::npos) << run.out;
  EXPECT_NE(result["warnings"].dump().find("jumps of 2π were unwrapped"), std::string::npos)
      << result["warnings"];
  EXPECT_NE(result["verdict"], "trusted");
}

}  // namespace

// A robot's recording (a scans directory, as a bag's joints) with the wheel joints swapped or one
// reversed: named before the calibration would fail on it.
TEST_F(InputSanityCliTest, RecordingWheelJointsSwappedOrReversedAreNamed) {
  const fs::path good = dir_ / "scans";
  const CliRun simulated =
      Calib("simulate --beams 180 --intervals 200 --seed 5 --output " + good.string());
  ASSERT_EQ(simulated.exit_code, 0) << simulated.err;
  const auto variant = [&](const std::string& name,
                           const std::function<void(std::vector<double>*)>& edit) {
    const fs::path dir = dir_ / name;
    fs::create_directories(dir);
    fs::copy_file(good / "scans.csv", dir / "scans.csv");
    RewriteCsv(good / "odometry.csv", dir / "odometry.csv",
               [&](const std::vector<std::string>&, std::vector<double>* row) { edit(row); });
    return dir;
  };
  const fs::path swapped =
      variant("swapped", [](std::vector<double>* row) { std::swap((*row)[1], (*row)[2]); });
  ExpectRefused(Calib(Calibrate(swapped)),
                {"swapped: the wheels turn the robot the wrong way", "'left_wheel'",
                 "swapped the log fits a robot", "both negated"});
  const fs::path reversed =
      variant("reversed", [](std::vector<double>* row) { (*row)[2] = -(*row)[2]; });
  const CliRun run = Calib(Calibrate(reversed));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("the right wheel's readings have the wrong sign"), std::string::npos)
      << run.err;
  EXPECT_EQ(run.err.find("swapped"), std::string::npos) << run.err;
}
