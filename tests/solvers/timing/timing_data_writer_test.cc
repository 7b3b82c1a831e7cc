// Generators of data/timing's stream logs, disabled: run them with
// --gtest_also_run_disabled_tests (see data/timing/README.md).
#include <calib/core/laser/laser_log_io.h>
#include <calib/tools/report/stream_timing_report.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/solvers/timing/timing_data_recipes.h"

namespace calib {
namespace {

namespace fs = std::filesystem;

using ::calib::testing::FitStampAsTruth;
using ::calib::testing::Generate;
using ::calib::testing::StampAsTruthFit;
using ::calib::testing::TimingGenerated;
using ::calib::testing::TimingRecipe;
using ::calib::testing::TimingRecipes;

void PrintFit(const char* label, const StampAsTruthFit& fit) {
  const LaserParamVector& z = fit.error_sigmas;
  std::printf(
      "%-14s z r_l %+6.2f r_r %+6.2f b %+6.2f x %+6.2f y %+6.2f th %+6.2f  noise %.4f %.4f %.4f\n",
      label, z(0), z(1), z(2), z(3), z(4), z(5), fit.result.noise_sigma[0](0),
      fit.result.noise_sigma[0](1), fit.result.noise_sigma[0](2));
}

nlohmann::ordered_json TruthJson(const TimingRecipe& recipe, const TimingGenerated& g) {
  const LaserSimTruth& t = g.truth;
  const LaserSimOptions& s = recipe.sim;
  const LoggingModel& m = recipe.logging;
  const LoggedTimingTruth& timing = g.timing;
  nlohmann::ordered_json json;
  json["problem"] = "laser";
  json["estimate"] = {{"r_l", t.odometry.left_radius_m}, {"r_r", t.odometry.right_radius_m},
                      {"b", t.odometry.wheelbase_m},     {"sensor_x", t.base_T_sensor(0)},
                      {"sensor_y", t.base_T_sensor(1)},  {"sensor_theta", t.base_T_sensor(2)}};
  json["simulation"] = {{"intervals", s.num_intervals},
                        {"seed", s.seed},
                        {"trajectory", "rich"},
                        {"noise_xy", s.scan_noise_sigma(0)},
                        {"noise_theta", s.scan_noise_sigma(2)},
                        {"speed_time_constant", s.speed_time_constant_s},
                        {"segment_mean", s.segment_mean_s},
                        {"max_wheel_speed", s.max_wheel_speed},
                        {"calib_simulate_flags", recipe.cli}};
  json["logging"] = {{"sensor_period", m.sensor_period_s},
                     {"sensor_phase", m.sensor_phase_s},
                     {"sensor_drift", m.sensor_clock_drift},
                     {"logger_period", m.logger_period_s},
                     {"logger_jitter", m.logger_jitter_s},
                     {"pickup_latency", m.pickup_latency_s},
                     {"encoder_period", m.encoder_period_s},
                     {"encoder_poll_jitter", m.encoder_poll_jitter_s},
                     {"encoder_stamp_jitter", m.encoder_stamp_jitter_s},
                     {"repeat_fraction", m.repeat_fraction}};
  json["stamp_as_truth_biased"] = recipe.biased;
  json["timing"] = LoggedTimingTruthJson(timing);
  return json;
}

// Writes data/timing (run with --gtest_also_run_disabled_tests; see data/timing/README.md).
TEST(TimingData, DISABLED_WriteDataFiles) {
  for (const TimingRecipe& recipe : TimingRecipes()) {
    const fs::path dir = ::calib::testing::TimingDataDir() / recipe.name;
    const TimingGenerated g = Generate(recipe);
    const Status written =
        WriteLaserStream(g.streams.odometry, g.streams.sensor_poses, dir.string());
    ASSERT_TRUE(written.ok()) << written.message();
    std::ofstream(dir / "truth.json") << TruthJson(recipe, g).dump(1) << "\n";
    const StatusOr<StampAsTruthFit> fit = FitStampAsTruth(g.streams, g.truth);
    ASSERT_TRUE(fit.ok()) << fit.message();
    PrintFit(recipe.name.c_str(), *fit);
  }
}

// Seed survey (CALIB_SEEDS=n): the stamp-as-truth errors of every recipe's settings.
TEST(TimingData, DISABLED_SurveySeeds) {
  const int seeds = std::getenv("CALIB_SEEDS") ? std::atoi(std::getenv("CALIB_SEEDS")) : 8;
  const char* speed = std::getenv("CALIB_SPEED");  // Overrides, for exploring the settings.
  const char* intervals = std::getenv("CALIB_INTERVALS");
  const char* noise = std::getenv("CALIB_NOISE_SCALE");
  for (TimingRecipe recipe : TimingRecipes()) {
    if (speed != nullptr) recipe.sim.max_wheel_speed = std::atof(speed);
    if (intervals != nullptr) recipe.sim.num_intervals = std::atoi(intervals);
    if (noise != nullptr) recipe.sim.scan_noise_sigma *= std::atof(noise);
    if (const char* jitter = std::getenv("CALIB_LOGGER_JITTER"); jitter && recipe.biased) {
      recipe.logging.logger_jitter_s = std::atof(jitter);
    }
    for (int seed = 1; seed <= seeds; ++seed) {
      recipe.sim.seed = seed;
      const TimingGenerated g = Generate(recipe);
      const StatusOr<StampAsTruthFit> fit = FitStampAsTruth(g.streams, g.truth);
      ASSERT_TRUE(fit.ok()) << fit.message();
      char label[64];
      std::snprintf(label, sizeof(label), "%s/%d", recipe.name.c_str(), seed);
      PrintFit(label, *fit);
    }
  }
}

}  // namespace
}  // namespace calib
