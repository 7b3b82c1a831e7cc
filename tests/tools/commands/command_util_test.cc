// What every command shares: progress lines and --quiet, the loss flags, the default paths.
#include <calib/tools/commands/command_util.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

namespace calib::cli {
namespace {

// What the printer wrote into a temporary file.
std::string Printed(bool quiet, double after_s) {
  std::FILE* file = std::tmpfile();
  const Stopwatch clock;
  const auto progress = ProgressPrinter(clock, quiet, file, after_s);
  progress("refinement round 1");
  progress("refinement round 2");
  std::string text(256, '\0');
  std::rewind(file);
  text.resize(std::fread(text.data(), 1, text.size(), file));
  std::fclose(file);
  return text;
}

TEST(CommandUtilTest, ProgressPrintsOnlyLongRunsAndNothingWhenQuiet) {
  const std::string loud = Printed(/*quiet=*/false, /*after_s=*/-1.0);
  EXPECT_EQ(loud.rfind("calib: ", 0), 0u) << loud;
  EXPECT_NE(loud.find(" s: refinement round 1\n"), std::string::npos) << loud;
  EXPECT_NE(loud.find(" s: refinement round 2\n"), std::string::npos) << loud;
  EXPECT_EQ(Printed(/*quiet=*/true, /*after_s=*/-1.0), "");
  EXPECT_EQ(Printed(/*quiet=*/false, /*after_s=*/1e9), "");
}

TEST(CommandUtilTest, LossFlags) {
  ASSERT_TRUE(ParseLossFlags("huber", 2.0).ok());
  EXPECT_EQ(*ParseLossFlags("huber", 2.0), RobustLoss::kHuber);
  const StatusOr<RobustLoss> banana = ParseLossFlags("banana", 2.0);
  ASSERT_FALSE(banana.ok());
  EXPECT_NE(banana.message().find("banana"), std::string::npos);
  EXPECT_EQ(ParseLossFlags("cauchy", 0.0).message(), "--loss_scale must be positive");
  EXPECT_EQ(ParseLossFlags("cauchy", -1.0).status().code(), StatusCode::kInvalidInput);
}

TEST(CommandUtilTest, InputRequiredOutputOptional) {
  EXPECT_TRUE(CheckInput("a.tuple").ok());
  EXPECT_EQ(CheckInput("").message(), "--input is required");
}

TEST(CommandUtilTest, PathsAndLists) {
  EXPECT_EQ(DefaultPlotsDir("out/diag.json"), "out/diag_plots");
  EXPECT_EQ(DefaultPlotsDir("diag.json"), "diag_plots");
  EXPECT_EQ(SplitCommas("a,,b,"), (std::vector<std::string>{"a", "b"}));
  EXPECT_TRUE(SplitCommas("").empty());
  EXPECT_FALSE(IsBearingInput("/nonexistent", "auto"));
  EXPECT_FALSE(IsBearingInput(CALIB_SOURCE_DIR "/data/sample_bearing", "csv"));
  EXPECT_TRUE(IsBearingInput(CALIB_SOURCE_DIR "/data/sample_bearing", "auto"));
}

TEST(CommandUtilTest, FailReturnsOne) { EXPECT_EQ(Fail("test message"), 1); }

}  // namespace
}  // namespace calib::cli
