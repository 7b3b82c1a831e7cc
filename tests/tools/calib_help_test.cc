// The contract's command line: `calib -h`, `calib --help`, `calib COMMAND --help` (that
// command's flags only) and `calib --version`.
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>
#include <string>

#include "tests/tools/cli_runner.h"

namespace calib {
namespace {

using testing::CliRun;
using testing::MakeScratchDir;
using testing::RunCalib;

class CalibHelpTest : public ::testing::Test {
 protected:
  void SetUp() override { scratch_ = MakeScratchDir("calib_help_"); }
  void TearDown() override { std::filesystem::remove_all(scratch_); }
  std::filesystem::path scratch_;
};

TEST_F(CalibHelpTest, ShortAndLongHelpListTheCommands) {
  for (const std::string args : {"-h", "--help", "help"}) {
    const CliRun run = RunCalib(args, scratch_);
    EXPECT_EQ(run.exit_code, 0) << args;
    for (const char* command : {"calibrate", "diagnose", "simulate"}) {
      EXPECT_NE(run.out.find(command), std::string::npos) << args << ": " << run.out;
    }
  }
}

TEST_F(CalibHelpTest, CommandHelpListsThatCommandsFlagsOnly) {
  const CliRun calibrate = RunCalib("calibrate --help", scratch_);
  EXPECT_EQ(calibrate.exit_code, 0);
  EXPECT_NE(calibrate.out.find("--input"), std::string::npos);
  EXPECT_EQ(calibrate.out.find("--family_alpha"), std::string::npos);  // A diagnose flag.
  EXPECT_EQ(calibrate.out.find("--intervals"), std::string::npos);     // A simulate flag.
  EXPECT_EQ(calibrate.out.find("--flagfile"), std::string::npos);      // gflags' own.
  const CliRun diagnose = RunCalib("diagnose -h", scratch_);
  EXPECT_EQ(diagnose.exit_code, 0);
  EXPECT_NE(diagnose.out.find("--family_alpha"), std::string::npos);
  EXPECT_NE(diagnose.out.find("--input"), std::string::npos);
  const CliRun simulate = RunCalib("simulate --help", scratch_);
  EXPECT_EQ(simulate.exit_code, 0);
  EXPECT_NE(simulate.out.find("--intervals"), std::string::npos);
  EXPECT_EQ(simulate.out.find("--family_alpha"), std::string::npos);
}

TEST_F(CalibHelpTest, VersionIsANumber) {
  const CliRun run = RunCalib("--version", scratch_);
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_TRUE(std::regex_search(run.out, std::regex("[0-9]+\\.[0-9]+\\.[0-9]+"))) << run.out;
}

TEST_F(CalibHelpTest, NoCommandIsAUsageError) {
  const CliRun run = RunCalib("", scratch_);
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("calibrate"), std::string::npos);
}

}  // namespace
}  // namespace calib
