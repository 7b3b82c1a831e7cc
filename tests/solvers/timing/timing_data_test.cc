// data/timing: the files are what their recipes make, and taking the stamps as sample times
// biases the calibration on the robot-like log (≥ 5 σ in b or a radius) but not on the controls.
#include <calib/core/laser/laser_log_io.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/solvers/timing/timing_data_recipes.h"

namespace calib {
namespace {

using ::calib::testing::FitStampAsTruth;
using ::calib::testing::Generate;
using ::calib::testing::ReadStreamFiles;
using ::calib::testing::StampAsTruthFit;
using ::calib::testing::TimingDataDir;
using ::calib::testing::TimingGenerated;
using ::calib::testing::TimingRecipe;
using ::calib::testing::TimingRecipes;

class TimingDataTest : public ::testing::TestWithParam<TimingRecipe> {};

nlohmann::json ReadTruth(const TimingRecipe& recipe) {
  std::ifstream in(TimingDataDir() / recipe.name / "truth.json");
  return nlohmann::json::parse(in, nullptr, /*allow_exceptions=*/false);
}

TEST_P(TimingDataTest, FileMatchesItsRecipe) {
  const TimingRecipe& recipe = GetParam();
  const StatusOr<LaserStreams> file = ReadStreamFiles(TimingDataDir() / recipe.name);
  ASSERT_TRUE(file.ok()) << file.message();
  const TimingGenerated g = Generate(recipe);
  ASSERT_EQ(file->odometry.size(), g.streams.odometry.size());
  ASSERT_EQ(file->sensor_poses.size(), g.streams.sensor_poses.size());
  for (size_t k = 0; k < g.streams.odometry.size(); ++k) {
    ASSERT_EQ(file->odometry[k].t_s, g.streams.odometry[k].t_s) << k;
    ASSERT_EQ(file->odometry[k].left_rad, g.streams.odometry[k].left_rad) << k;
    ASSERT_EQ(file->odometry[k].right_rad, g.streams.odometry[k].right_rad) << k;
  }
  for (size_t k = 0; k < g.streams.sensor_poses.size(); ++k) {
    ASSERT_EQ(file->sensor_poses[k].t_s, g.streams.sensor_poses[k].t_s) << k;
    ASSERT_EQ(file->sensor_poses[k].world_T_sensor, g.streams.sensor_poses[k].world_T_sensor) << k;
  }
  const nlohmann::json truth = ReadTruth(recipe);
  ASSERT_FALSE(truth.is_discarded());
  EXPECT_EQ(truth["timing"]["sensor_sample_time"].get<std::vector<double>>(),
            g.timing.sensor_sample_time_s);
  EXPECT_EQ(truth["timing"]["encoder_sample_time"].get<std::vector<double>>(),
            g.timing.encoder_sample_time_s);
  EXPECT_EQ(truth["estimate"]["b"].get<double>(), g.truth.odometry.wheelbase_m);
}

// Stamps taken as sample times: on the robot-like log b or a radius is ≥ 5 σ off; on the
// controls (clean timing, same motion) every parameter is within 3 σ.
TEST_P(TimingDataTest, StampAsTruthCalibration) {
  const TimingRecipe& recipe = GetParam();
  const StatusOr<LaserStreams> file = ReadStreamFiles(TimingDataDir() / recipe.name);
  ASSERT_TRUE(file.ok()) << file.message();
  const TimingGenerated g = Generate(recipe);
  const StatusOr<StampAsTruthFit> fit = FitStampAsTruth(*file, g.truth);
  ASSERT_TRUE(fit.ok()) << fit.message();
  const LaserParamVector& z = fit->error_sigmas;
  const double wheels = std::max({std::abs(z(0)), std::abs(z(1)), std::abs(z(2))});
  if (recipe.biased) {
    EXPECT_GE(wheels, 5.0) << z.transpose();
  } else {
    EXPECT_LE(z.cwiseAbs().maxCoeff(), 3.0) << z.transpose();
  }
}

INSTANTIATE_TEST_SUITE_P(Logs, TimingDataTest, ::testing::ValuesIn(TimingRecipes()),
                         [](const ::testing::TestParamInfo<TimingRecipe>& info) {
                           return info.param.name;
                         });

}  // namespace
}  // namespace calib
