// `calib calibrate --plots_dir` and `calib diagnose` as a user runs them: the plot files, their
// structure, the words a person reads, and counts that agree with the JSON (skips without the
// binary).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/tools/cli_runner.h"
#include "tests/tools/svg_check.h"

namespace {

namespace fs = std::filesystem;

using ::calib::testing::CliRun;
using ::calib::testing::HasText;
using ::calib::testing::ReadFile;
using ::calib::testing::RunCalib;
using ::calib::testing::SvgSeriesPoints;
using ::calib::testing::SvgStructureError;

const fs::path kData = fs::path(CALIB_SOURCE_DIR) / "data";

class CalibratePlotsCliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(fs::path(CALIB_BINARY_DIR) / "bin" / "calib")) GTEST_SKIP() << "no calib";
    dir_ = ::calib::testing::MakeScratchDir("calib_plots_cli_test_");
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }

  // Calibrates `input` with `extra` flags; expects success and returns the JSON.
  nlohmann::json Calibrate(const fs::path& input, const std::string& extra) {
    const CliRun run = RunCalib("calibrate --input " + input.string() + " --output " +
                                    (dir_ / "out.json").string() + " " + extra,
                                dir_);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    summary_ = run.out;
    if (run.exit_code != 0) return nlohmann::json::object();
    return nlohmann::json::parse(ReadFile(dir_ / "out.json"));
  }

  // The SVG's text after checking that it is well formed.
  static std::string Svg(const fs::path& path) {
    EXPECT_TRUE(fs::exists(path)) << path;
    const std::string svg = ReadFile(path);
    EXPECT_EQ(SvgStructureError(svg), "") << path;
    return svg;
  }

  fs::path dir_;
  std::string summary_;
};

TEST_F(CalibratePlotsCliTest, NoPlotsUnlessAsked) {
  const nlohmann::json json = Calibrate(kData / "sample_laser.tuple", "--quiet");
  EXPECT_FALSE(json.contains("plots"));
  EXPECT_FALSE(fs::exists(dir_ / "out_plots"));
}

TEST_F(CalibratePlotsCliTest, LaserLogGivesPathsResidualsAndCoverage) {
  const fs::path plots = dir_ / "plots";
  const nlohmann::json json =
      Calibrate(kData / "sample_laser.tuple", "--plots_dir " + plots.string());
  ASSERT_TRUE(json.contains("plots"));
  EXPECT_EQ(json["plots"].size(), 3u);
  EXPECT_NE(summary_.find("plot: " + (plots / "laser_paths.svg").string()), std::string::npos);

  const std::string paths = Svg(plots / "laser_paths.svg");
  EXPECT_TRUE(HasText(paths, "Dead reckoning before and after calibration"));
  EXPECT_TRUE(HasText(paths, "x [m] (sensor frame at the start)"));
  EXPECT_TRUE(HasText(paths, "closed-form seed"));  // Tuples carry no nominal wheels.
  EXPECT_TRUE(HasText(paths, "scan matching"));

  const std::string residuals = Svg(plots / "laser_residuals.svg");
  for (const char* text : {"x error [mm]", "y error [mm]", "θ error [mrad]", "intervals per bin",
                           "rejected (outliers)", "normal, σ ="}) {
    EXPECT_TRUE(HasText(residuals, text)) << text;
  }

  const std::string coverage = Svg(plots / "laser_coverage.svg");
  EXPECT_TRUE(HasText(coverage, "v, forward speed [m/s]"));
  EXPECT_TRUE(HasText(coverage, "ω, turn rate [deg/s]"));
  const auto counts = SvgSeriesPoints(coverage);
  const int samples = json["samples"], inliers = json["inliers"];
  EXPECT_EQ(counts.at("used"), inliers);
  EXPECT_EQ(counts.at("rejected (outliers)"), samples - inliers);
  EXPECT_GT(samples - inliers, 0);  // The sample log has slips.
}

TEST_F(CalibratePlotsCliTest, BearingLogGivesPathsResidualsAndCoverage) {
  const fs::path plots = dir_ / "plots";
  const nlohmann::json json =
      Calibrate(kData / "sample_bearing", "--quiet --plots_dir " + plots.string());
  ASSERT_TRUE(json.contains("plots"));

  const std::string paths = Svg(plots / "bearing_paths.svg");
  EXPECT_TRUE(HasText(paths, "Robot paths: dead reckoning before and after calibration"));
  EXPECT_TRUE(HasText(paths, "x [m]"));  // The sample gives an initial distance: metres.
  EXPECT_TRUE(HasText(paths, "nominal wheels"));
  EXPECT_TRUE(HasText(paths, "Run 1"));

  const std::string residuals = Svg(plots / "bearing_residuals.svg");
  EXPECT_TRUE(HasText(residuals, "bearing error [deg]"));
  EXPECT_TRUE(HasText(residuals, "σβ ="));
  const int samples = json["samples"], inliers = json["inliers"];
  EXPECT_TRUE(HasText(residuals, std::to_string(inliers) + " used, " +
                                     std::to_string(samples - inliers) + " rejected"));

  const std::string coverage = Svg(plots / "bearing_coverage.svg");
  EXPECT_TRUE(HasText(coverage, "v, forward speed [m/s]"));
  EXPECT_TRUE(HasText(coverage, "distance [m]"));
  // One step per bearing after each run's first node.
  const auto counts = SvgSeriesPoints(coverage);
  EXPECT_LE(counts.at("used"), inliers);
  EXPECT_LE(counts.at("rejected (outliers)"), samples - inliers);
  EXPECT_GE(counts.at("used") + counts.at("rejected (outliers)"), samples - 3);  // 3 runs.
}

TEST_F(CalibratePlotsCliTest, PngWhenAskedOrAClearError) {
  const fs::path plots = dir_ / "plots";
  const CliRun bad = RunCalib(
      "calibrate --quiet --input " + (kData / "sample_laser.tuple").string() + " --output " +
          (dir_ / "out.json").string() + " --plots_dir " + plots.string() + " --plot_format gif",
      dir_);
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("--plot_format 'gif' (svg or png)"), std::string::npos) << bad.err;
  if (std::system("command -v rsvg-convert >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "rsvg-convert is not installed";
  }
  Calibrate(kData / "sample_laser.tuple",
            "--quiet --plot_format png --plots_dir " + plots.string());
  for (const char* name : {"laser_paths", "laser_residuals", "laser_coverage"}) {
    EXPECT_TRUE(fs::exists(plots / (std::string(name) + ".svg"))) << name;
    const std::string png = ReadFile(plots / (std::string(name) + ".png"));
    EXPECT_EQ(png.substr(1, 3), "PNG") << name;
  }
}

TEST_F(CalibratePlotsCliTest, PngWithoutTheRasterizerNamesItsPackage) {
  const fs::path plots = dir_ / "plots";
  // With an empty PATH the program cannot be found (run through env, which needs no PATH).
  const std::string command =
      "env PATH= " + std::string(CALIB_BINARY_DIR) + "/bin/calib calibrate --quiet --input " +
      (kData / "sample_laser.tuple").string() + " --output " + (dir_ / "out2.json").string() +
      " --plots_dir " + plots.string() + " --plot_format png 2>" + (dir_ / "err.txt").string();
  EXPECT_NE(std::system(command.c_str()), 0);
  const std::string err = ReadFile(dir_ / "err.txt");
  EXPECT_NE(err.find("rsvg-convert"), std::string::npos) << err;
  EXPECT_NE(err.find("librsvg2-bin"), std::string::npos) << err;
}

TEST_F(CalibratePlotsCliTest, DiagnosePlotsSpeakInWords) {
  const CliRun run =
      RunCalib("diagnose --quiet --input " + (kData / "diagnose" / "lateral_slip.tuple").string() +
                   " --output " + (dir_ / "diag.json").string(),
               dir_);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const std::string svg = Svg(dir_ / "diag_plots" / "lateral_slip_vs_v_times_omega.svg");
  EXPECT_TRUE(HasText(svg, "Lateral slip: residuals against v·ω (centripetal acceleration)"));
  EXPECT_TRUE(HasText(svg, "Residual along the effect: each sample"));  // The caption.
  EXPECT_TRUE(HasText(svg, "Forward (x) residual"));
  // Bins of equal count are numbered (their means crowd near zero) and their means listed.
  EXPECT_TRUE(HasText(svg, "bin of equal count, by v·ω"));
  EXPECT_FALSE(HasText(svg, "lateral_slip"));
  const std::string time = Svg(dir_ / "diag_plots" / "residuals_vs_time.svg");
  EXPECT_TRUE(HasText(time, "time [s] (bin means)"));  // Evenly spread: true positions.
}

}  // namespace
