// Generators of data/diagnose's laser logs, disabled: run them with
// --gtest_also_run_disabled_tests (see data/diagnose/README.md).
#include <calib/core/laser/laser_log_io.h>
#include <calib/solvers/laser/laser_diagnosis.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "tests/solvers/laser/laser_diagnosis_recipes.h"

namespace calib {
namespace {

namespace fs = std::filesystem;

using ::calib::testing::Concealment;
using ::calib::testing::Generate;
using ::calib::testing::Generated;
using ::calib::testing::MeasureConcealment;
using ::calib::testing::Recipe;
using ::calib::testing::Recipes;

const fs::path kDataDir = ::calib::testing::DiagnoseDataDir();

nlohmann::ordered_json TruthJson(const Recipe& recipe, const Generated& g) {
  const LaserSimTruth& t = g.truth;
  nlohmann::ordered_json json;
  json["problem"] = "laser";
  json["estimate"] = {{"r_l", t.odometry.left_radius_m}, {"r_r", t.odometry.right_radius_m},
                      {"b", t.odometry.wheelbase_m},     {"sensor_x", t.base_T_sensor(0)},
                      {"sensor_y", t.base_T_sensor(1)},  {"sensor_theta", t.base_T_sensor(2)}};
  json["effects"] = {{"time_offset", t.effects.time_offset_s},
                     {"lateral_slip", t.effects.lateral_slip_s},
                     {"longitudinal_slip", t.effects.longitudinal_slip_s},
                     {"wheel_radius_change", t.effects.radius_change_time_s},
                     {"r_l_after", t.effects.left_radius_after_m},
                     {"r_r_after", t.effects.right_radius_after_m},
                     {"speed_dependent_radius", recipe.speed_radius},
                     {"speed_reference", g.speed_reference}};
  nlohmann::ordered_json expected = nlohmann::ordered_json::array();
  for (LaserEffect e : recipe.effects) expected.push_back(LaserEffectName(e));
  json["expected_effects"] = expected;
  json["concealed"] = recipe.concealed;
  const LaserSimOptions& s = recipe.sim;
  json["simulation"] = {{"intervals", s.num_intervals},
                        {"seed", s.seed},
                        {"trajectory", "rich"},
                        {"noise_xy", s.scan_noise_sigma(0)},
                        {"noise_theta", s.scan_noise_sigma(2)},
                        {"outliers", s.outlier_fraction},
                        {"speed_time_constant_s", s.speed_time_constant_s},
                        {"segment_mean_s", s.segment_mean_s},
                        {"max_wheel_speed", s.max_wheel_speed},
                        {"forward_only", recipe.forward_only},
                        {"calib_simulate_flags", recipe.cli}};
  return json;
}

// Writes data/diagnose (run with --gtest_also_run_disabled_tests; see data/diagnose/README.md).
TEST(LaserDiagnosisData, DISABLED_WriteDataFiles) {
  fs::create_directories(kDataDir);
  for (const Recipe& recipe : Recipes()) {
    const Generated g = Generate(recipe, true);
    ASSERT_LE(g.log.intervals.size(), 2000u) << recipe.name;
    const Status written = WriteLaserTuples(g.log, (kDataDir / (recipe.name + ".tuple")).string());
    ASSERT_TRUE(written.ok()) << written.message();
    std::ofstream truth(kDataDir / (recipe.name + "_truth.json"));
    truth << TruthJson(recipe, g).dump(2) << "\n";
    const Concealment c = MeasureConcealment(recipe);
    std::printf(
        "%-30s %5zu intervals  σ ratio %.3f %.3f %.3f  max |error|/σ %.2f  max |shift|/σ %.2f\n",
        recipe.name.c_str(), g.log.intervals.size(), c.sigma_ratio(0), c.sigma_ratio(1),
        c.sigma_ratio(2), c.error_sigmas.cwiseAbs().maxCoeff(),
        c.shift_sigmas.cwiseAbs().maxCoeff());
  }
}

// Seed survey of a recipe (CALIB_SURVEY=name, CALIB_SEEDS=n): concealment and diagnosis.
TEST(LaserDiagnosisData, DISABLED_SurveySeeds) {
  const char* name = std::getenv("CALIB_SURVEY");
  const int seeds = std::getenv("CALIB_SEEDS") ? std::atoi(std::getenv("CALIB_SEEDS")) : 8;
  for (Recipe recipe : Recipes()) {
    if (name == nullptr || recipe.name != name) continue;
    for (int seed = 1; seed <= seeds; ++seed) {
      recipe.sim.seed = seed;
      const Concealment c = MeasureConcealment(recipe);
      const Generated g = Generate(recipe, true);
      const StatusOr<LaserDiagnosis> d = DiagnoseLaser(g.log.intervals, LaserDiagnosisOptions());
      ASSERT_TRUE(d.ok());
      const LaserCalibration truth{g.truth.odometry, g.truth.base_T_sensor};
      const LaserParamVector z =
          (d->final_fit.estimate.ToVector() - truth.ToVector()).cwiseQuotient(d->final_fit.stddev);
      std::printf(
          "seed %d σ ratio %.3f %.3f %.3f max|error| %.2f max|shift| %.2f final max|z| %.2f:", seed,
          c.sigma_ratio(0), c.sigma_ratio(1), c.sigma_ratio(2),
          c.error_sigmas.cwiseAbs().maxCoeff(), c.shift_sigmas.cwiseAbs().maxCoeff(),
          z.cwiseAbs().maxCoeff());
      for (const LaserFinding& f : d->findings) {
        if (f.significant) std::printf(" %s %.4g±%.2g", f.name.c_str(), f.value, f.stddev);
      }
      std::printf("\n");
    }
  }
}

}  // namespace
}  // namespace calib
