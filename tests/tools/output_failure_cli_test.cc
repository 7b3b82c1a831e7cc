// Every output failure is an error, in every command: an output path in a folder that does not
// exist, a folder given as the file, a folder the tool may not write in, a full disk (/dev/full:
// writes fail at flush or close) and a standard output that cannot take what is printed each give
// a non-zero exit (never a crash, never 0) and a message naming the path (skips without the
// binary).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/tools/cli_runner.h"

namespace {

namespace fs = std::filesystem;

using ::calib::testing::CliRun;
using ::calib::testing::ReadFile;
using ::calib::testing::RunCalib;

const fs::path kData = fs::path(CALIB_SOURCE_DIR) / "data";
const std::string kLaser = (kData / "sample_laser.tuple").string();
const std::string kBearing = (kData / "sample_bearing").string();

class OutputFailureCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(fs::path(CALIB_BINARY_DIR) / "bin" / "calib")) GTEST_SKIP() << "no calib";
    dir_ = ::calib::testing::MakeScratchDir("calib_output_failure_cli_test_");
  }
  void TearDown() override {
    if (dir_.empty()) return;
    std::error_code ignored;
    fs::permissions(dir_ / "read_only", fs::perms::owner_all, ignored);
    fs::remove_all(dir_);
  }

  // A folder this process cannot create files in: a folder without write permission, or /proc
  // for a user (root) whom permissions do not stop.
  fs::path ReadOnlyFolder() {
    const fs::path folder = dir_ / "read_only";
    fs::create_directory(folder);
    fs::permissions(folder, fs::perms::owner_read | fs::perms::owner_exec);
    return ::access(folder.c_str(), W_OK) == 0 ? fs::path("/proc") : folder;
  }

  // Runs `args`; expects a clean failure (an exit status, not a signal, and not 0) whose error
  // names `path`.
  void ExpectFailureNaming(const std::string& args, const std::string& path) {
    const CliRun run = RunCalib(args, dir_, dir_);
    EXPECT_GT(run.exit_code, 0) << args << "\n" << run.err;
    EXPECT_NE(run.err.find("calib: error:"), std::string::npos) << args << "\n" << run.err;
    EXPECT_NE(run.err.find(path), std::string::npos) << args << "\n" << run.err;
  }

  // Runs `args` with its standard output on a full disk; expects a clean failure saying so.
  void ExpectStdoutFailure(const std::string& args) {
    const fs::path err = dir_ / "stderr.txt";
    const std::string command = "cd " + dir_.string() + " && " + std::string(CALIB_BINARY_DIR) +
                                "/bin/calib " + args + " >/dev/full 2>" + err.string() +
                                " </dev/null";
    const int status = std::system(command.c_str());
    ASSERT_TRUE(WIFEXITED(status)) << args << ": killed by a signal";
    EXPECT_NE(WEXITSTATUS(status), 0) << args;
    const std::string said = ReadFile(err);
    EXPECT_NE(said.find("calib: error:"), std::string::npos) << args << "\n" << said;
    EXPECT_TRUE(said.find("standard output") != std::string::npos ||
                said.find("stdout") != std::string::npos)
        << args << "\n"
        << said;
  }

  // The unwritable places for a file named `name`, each run as `before` PATH `after`: a folder
  // that does not exist, a full disk, a folder where the file should be (unless the output is
  // itself a folder) and a folder that refuses new files.
  void ExpectEveryUnwritableFileFails(const std::string& before, const std::string& after,
                                      const std::string& name, bool output_is_a_folder = false) {
    std::vector<std::string> paths = {(dir_ / "no_such_folder" / name).string(), "/dev/full",
                                      (ReadOnlyFolder() / name).string()};
    if (!output_is_a_folder) {
      fs::create_directories(dir_ / "taken" / name);
      paths.push_back((dir_ / "taken" / name).string());
    }
    for (const std::string& path : paths) {
      SCOPED_TRACE(path);
      // In the refusing folder the first file to fail may be another one (diagnose's plots).
      const bool read_only = fs::path(path).parent_path() == ReadOnlyFolder();
      ExpectFailureNaming(before + path + after,
                          read_only ? ReadOnlyFolder().string() + "/" : path);
    }
    EXPECT_FALSE(fs::exists(dir_ / "no_such_folder"));
  }

  fs::path dir_;
};

TEST_F(OutputFailureCliTest, CalibrateLaserOutput) {
  ExpectEveryUnwritableFileFails("calibrate --input " + kLaser + " --output ", " --quiet",
                                 "out.json");
}

TEST_F(OutputFailureCliTest, CalibrateFullDiskSaysWhy) {
  const CliRun run =
      RunCalib("calibrate --input " + kLaser + " --output /dev/full --quiet", dir_, dir_);
  EXPECT_EQ(run.exit_code, 1) << run.err;
  EXPECT_NE(run.err.find("/dev/full: No space left on device"), std::string::npos) << run.err;
}

TEST_F(OutputFailureCliTest, CalibrateBearingOutput) {
  ExpectEveryUnwritableFileFails("calibrate --input " + kBearing + " --output ", " --quiet",
                                 "out.json");
}

TEST_F(OutputFailureCliTest, CalibrateStandardOutput) {
  ExpectStdoutFailure("calibrate --input " + kLaser + " --output - --quiet");
  ExpectStdoutFailure("calibrate --input " + kLaser);  // The summary.
  ExpectStdoutFailure("calibrate --input " + kLaser + " --output out.json");
  ExpectStdoutFailure("calibrate --input " + kBearing + " --output -");
}

TEST_F(OutputFailureCliTest, CalibrateExport) {
  // The export files go beside OUT.json: OUT.yaml taken by a folder, or a folder that refuses.
  fs::create_directory(dir_ / "out.yaml");
  const std::string json = (dir_ / "out.json").string();
  ExpectFailureNaming("calibrate --input " + kLaser + " --output " + json + " --export yaml",
                      (dir_ / "out.yaml").string());
  const std::string read_only = (ReadOnlyFolder() / "out.json").string();
  ExpectFailureNaming("calibrate --input " + kLaser + " --output " + read_only + " --export all",
                      (ReadOnlyFolder() / "out.").string());
  // Without --output they go to the working directory: calib_calibration.urdf is a folder here.
  fs::create_directory(dir_ / "calib_calibration.urdf");
  ExpectFailureNaming("calibrate --input " + kLaser + " --export urdf --quiet",
                      "calib_calibration.urdf");
}

TEST_F(OutputFailureCliTest, CalibrateExportBesideADeviceGoesToTheWorkingDirectory) {
  // Nothing is created beside /dev/full; the JSON's failure is still an error.
  ExpectFailureNaming("calibrate --input " + kLaser + " --output /dev/full --export yaml",
                      "/dev/full");
  EXPECT_FALSE(fs::exists("/dev/full.yaml"));
  EXPECT_TRUE(fs::exists(dir_ / "calib_calibration.yaml"));
}

TEST_F(OutputFailureCliTest, CalibratePlotsDir) {
  const std::string run = "calibrate --input " + kLaser + " --output " +
                          (dir_ / "out.json").string() + " --quiet --plots_dir ";
  ExpectFailureNaming(run + "/dev/full", "/dev/full");
  const std::string file = (dir_ / "a_file").string();
  fs::copy_file(kLaser, file);
  ExpectFailureNaming(run + file, file);
  const std::string read_only = (ReadOnlyFolder() / "plots").string();
  ExpectFailureNaming(run + read_only, read_only);
  // One plot's file name taken by a folder.
  fs::create_directories(dir_ / "plots" / "laser_paths.svg");
  ExpectFailureNaming(run + (dir_ / "plots").string(),
                      (dir_ / "plots" / "laser_paths.svg").string());
  // A plot folder that does not exist yet is made.
  const CliRun made = RunCalib(run + (dir_ / "new" / "plots").string(), dir_, dir_);
  EXPECT_EQ(made.exit_code, 0) << made.err;
  EXPECT_TRUE(fs::exists(dir_ / "new" / "plots" / "laser_paths.svg"));
}

TEST_F(OutputFailureCliTest, DiagnoseLaserOutput) {
  ExpectEveryUnwritableFileFails("diagnose --input " + kLaser + " --output ", " --quiet",
                                 "out.json");
  // No plot folder is made beside a device.
  EXPECT_FALSE(fs::exists("/dev/full_plots"));
}

TEST_F(OutputFailureCliTest, DiagnoseBearingOutput) {
  ExpectEveryUnwritableFileFails("diagnose --input " + kBearing + " --output ", " --quiet",
                                 "out.json");
}

TEST_F(OutputFailureCliTest, DiagnoseStandardOutput) {
  ExpectStdoutFailure("diagnose --input " + kLaser + " --output - --quiet");
  ExpectStdoutFailure("diagnose --input " + kLaser);
}

TEST_F(OutputFailureCliTest, DiagnosePlots) {
  const std::string json = (dir_ / "out.json").string();
  const std::string run = "diagnose --input " + kLaser + " --quiet --output " + json;
  ExpectFailureNaming(run + " --plots_dir /dev/full", "/dev/full");
  const std::string read_only = (ReadOnlyFolder() / "plots").string();
  ExpectFailureNaming(run + " --plots_dir " + read_only, read_only);
  // The default plot folder, OUT_plots beside OUT.json, taken by a file.
  fs::copy_file(kLaser, dir_ / "out_plots");
  ExpectFailureNaming(run, (dir_ / "out_plots").string());
  EXPECT_FALSE(fs::exists(json));
}

TEST_F(OutputFailureCliTest, SimulateOutput) {
  for (const std::string name : {"log.tuple", "log.csv", "log_streams"}) {
    SCOPED_TRACE(name);
    ExpectEveryUnwritableFileFails("simulate --intervals 40 --output ", "", name,
                                   /*output_is_a_folder=*/name == "log_streams");
  }
  const CliRun full = RunCalib("simulate --intervals 40 --format csv --output /dev/full", dir_);
  EXPECT_NE(full.err.find("/dev/full: write failed (No space left on device)"), std::string::npos)
      << full.err;
  for (const std::string format : {"tuples", "csv", "stream"}) {
    ExpectFailureNaming("simulate --intervals 40 --output /dev/full --format " + format,
                        "/dev/full");
  }
  // A raw-stream directory whose odometry.csv is a folder.
  fs::create_directories(dir_ / "streams" / "odometry.csv");
  ExpectFailureNaming("simulate --intervals 40 --output " + (dir_ / "streams").string(),
                      (dir_ / "streams" / "odometry.csv").string());
}

TEST_F(OutputFailureCliTest, SimulateTruth) {
  ExpectEveryUnwritableFileFails(
      "simulate --intervals 40 --output " + (dir_ / "log.tuple").string() + " --truth ", "",
      "truth.json");
}

TEST_F(OutputFailureCliTest, SimulateScans) {
  const std::string run = "simulate --intervals 10 --beams 60 --output ";
  ExpectFailureNaming(run + "/dev/full", "/dev/full");
  ExpectFailureNaming(run + (dir_ / "no_such_folder" / "robot.json").string(),
                      (dir_ / "no_such_folder").string());
  const std::string read_only = (ReadOnlyFolder() / "robot.json").string();
  ExpectFailureNaming(run + read_only, read_only);
  fs::create_directories(dir_ / "robot" / "scans.csv");
  ExpectFailureNaming(run + (dir_ / "robot").string(), (dir_ / "robot" / "scans.csv").string());
  ExpectFailureNaming(run + (dir_ / "robot.json").string() + " --truth /dev/full", "/dev/full");
}

TEST_F(OutputFailureCliTest, HelpAndVersionOnAFullDisk) {
  ExpectStdoutFailure("--help");
  ExpectStdoutFailure("calibrate --help");
  ExpectStdoutFailure("--version");
}

}  // namespace
