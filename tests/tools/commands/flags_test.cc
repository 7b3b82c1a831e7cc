// The flags' defaults are the options structs' defaults.
#include <calib/tools/commands/flags.h>
#include <gtest/gtest.h>

namespace calib::cli {
namespace {

TEST(FlagsTest, DefaultsAreTheStructsDefaults) {
  const DiagnoseOptions d = DiagnoseOptionsFromFlags(), dd;
  EXPECT_EQ(d.input, dd.input);
  EXPECT_EQ(d.format, "auto");
  EXPECT_EQ(d.loss, "cauchy");
  EXPECT_EQ(d.loss_scale, 3.0);
  EXPECT_FALSE(d.quiet);
  EXPECT_EQ(d.family_alpha, 0.01);
  EXPECT_EQ(d.max_effects, 3);
  EXPECT_EQ(d.cv_blocks, 5);
  EXPECT_EQ(d.boundary_speeds, "auto");
  EXPECT_EQ(d.plots_dir, "");
  const CalibrateOptions c = CalibrateOptionsFromFlags();
  EXPECT_EQ(c.format, dd.format);
  EXPECT_EQ(c.loss_scale, dd.loss_scale);

  const SimulateOptions s = SimulateOptionsFromFlags(), sd;
  EXPECT_EQ(s.intervals, 2000);
  EXPECT_EQ(s.seed, 1u);
  EXPECT_EQ(s.trajectory, "rich");
  EXPECT_EQ(s.noise_xy, sd.noise_xy);
  EXPECT_EQ(s.noise_theta, sd.noise_theta);
  EXPECT_EQ(s.speed_time_constant, sd.speed_time_constant);
  EXPECT_EQ(s.segment_mean, sd.segment_mean);
  EXPECT_EQ(s.max_wheel_speed, sd.max_wheel_speed);
  EXPECT_EQ(s.radius_change_time, -1.0);
}

TEST(FlagsTest, ParsedFlagsReachTheOptions) {
  const char* args[] = {"calib",    "--input=a.tuple",  "--quiet", "--family_alpha=0.05",
                        "--seed=7", "--trajectory=arc", "diagnose"};
  int argc = 7;
  char** argv = const_cast<char**>(args);
  ParseFlags("usage", &argc, &argv);
  ASSERT_EQ(argc, 2);
  EXPECT_STREQ(argv[1], "diagnose");
  const DiagnoseOptions d = DiagnoseOptionsFromFlags();
  EXPECT_EQ(d.input, "a.tuple");
  EXPECT_TRUE(d.quiet);
  EXPECT_EQ(d.family_alpha, 0.05);
  EXPECT_TRUE(CalibrateOptionsFromFlags().quiet);
  EXPECT_EQ(SimulateOptionsFromFlags().seed, 7u);
  EXPECT_EQ(SimulateOptionsFromFlags().trajectory, "arc");
}

}  // namespace
}  // namespace calib::cli
