// `calib diagnose` for the bearing problem: the concealed time offset of
// data/diagnose found, and nothing adopted on the controls.
#include <calib/core/bearing/bearing_log_io.h>
#include <calib/core/bearing/bearing_simulator.h>
#include <calib/solvers/bearing/bearing_diagnosis.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/solvers/bearing/bearing_diagnosis_recipes.h"

namespace calib {
namespace {

namespace fs = std::filesystem;

using ::calib::testing::BearingRecipe;
using ::calib::testing::kClean;
using ::calib::testing::kTimeOffset;
using ::calib::testing::RecipeOptions;

const fs::path kDataDir = fs::path(CALIB_SOURCE_DIR) / "data" / "diagnose";

BearingLog ReadData(const std::string& name) {
  const StatusOr<BearingLog> log = ReadBearingLog((kDataDir / name).string());
  EXPECT_TRUE(log.ok()) << log.message();
  return log.ok() ? *log : BearingLog{};
}

BearingParamVector TruthVector(const fs::path& truth_file) {
  std::ifstream in(truth_file);
  const nlohmann::json truth = nlohmann::json::parse(in);
  BearingParamVector v;
  for (int i = 0; i < kNumBearingParams; ++i) v(i) = truth["estimate"][kBearingParamNames[i]];
  return v;
}

double ParamError(int i, double estimate, double truth) {
  return i < 2 ? WrapAngle(estimate - truth) : estimate - truth;
}

nlohmann::json TruthJson(const BearingRecipe& recipe) {
  BearingSimTruth truth;
  SimulateBearingLog(RecipeOptions(recipe), &truth);
  nlohmann::json json;
  json["problem"] = "bearing";
  const BearingParamVector p = ToVector(truth.params);
  const BearingMetricVector m = ToVector(truth.metric);
  for (int i = 0; i < kNumBearingParams; ++i) json["estimate"][kBearingParamNames[i]] = p(i);
  for (int i = 2; i < kNumBearingMetricParams; ++i) {
    json["estimate"][kBearingMetricNames[i]] = m(i);
  }
  json["effects"]["time_offset"] = recipe.time_offset_s;
  json["expected_effects"] = recipe.time_offset_s != 0.0 ? nlohmann::json::array({"time_offset"})
                                                         : nlohmann::json::array();
  json["concealed"] = recipe.time_offset_s != 0.0;
  const BearingSimOptions o = RecipeOptions(recipe);
  json["simulation"] = {
      {"setting",
       "one run of 300 s at 5 cm/s nominal, turn rate 0.18·sin(2πt/80 s) rad/s, start (0, -1, 0) "
       "with the landmark 1 m to the left (tests/bearing_diagnosis_test.cc, RecipeOptions)"},
      {"wheel_radius", o.wheel_radius_m},
      {"wheelbase", o.wheelbase_m},
      {"encoder_rate_hz", o.encoder_rate_hz},
      {"encoder_noise_k", o.encoder_noise_k},
      {"bearing_rate_hz", o.bearing_rate_hz},
      {"bearing_noise_rad", o.bearing_noise_rad},
      {"initial_distance_run", o.initial_distance_run},
      {"seed", recipe.seed}};
  return json;
}

// Writes the bearing logs of data/diagnose (run with --gtest_also_run_disabled_tests).
TEST(BearingDiagnosisData, DISABLED_WriteDataFiles) {
  for (const BearingRecipe& recipe : {kTimeOffset, kClean}) {
    const fs::path dir = kDataDir / recipe.name;
    BearingLog log = SimulateBearingLog(RecipeOptions(recipe));
    ASSERT_TRUE(WriteBearingLog(log, dir.string()).ok());
    std::ofstream(dir / "truth.json") << TruthJson(recipe).dump(2) << "\n";
  }
}

// The data file is what the recipe makes (so the concealment below is measured on it).
TEST(BearingDiagnosisData, FilesMatchTheirRecipes) {
  for (const BearingRecipe& recipe : {kTimeOffset, kClean}) {
    const BearingLog file = ReadData(recipe.name);
    const BearingLog made = SimulateBearingLog(RecipeOptions(recipe));
    ASSERT_EQ(file.runs.size(), made.runs.size());
    ASSERT_EQ(file.runs[0].bearings.size(), made.runs[0].bearings.size());
    for (size_t j = 0; j < made.runs[0].bearings.size(); ++j) {
      ASSERT_NEAR(file.runs[0].bearings[j].bearing_rad, made.runs[0].bearings[j].bearing_rad,
                  1e-12);
    }
  }
}

// Concealed: the base fit's bearing RMS is within 5 % of the same log's without the offset,
// while a base parameter is ≥ 3 σ off; the diagnosis adopts time_offset within 3 σ of the truth
// and brings every parameter back within 2 σ.
TEST(BearingDiagnosisData, FindsTheConcealedTimeOffset) {
  const BearingLog log = ReadData(kTimeOffset.name);
  const BearingParamVector truth = TruthVector(kDataDir / kTimeOffset.name / "truth.json");
  const StatusOr<BearingDiagnosis> d = DiagnoseBearing(log);
  ASSERT_TRUE(d.ok()) << d.message();

  BearingRecipe twin = kTimeOffset;
  twin.time_offset_s = 0.0;
  const StatusOr<BearingCalibrationResult> clean =
      CalibrateBearing(SimulateBearingLog(RecipeOptions(twin)));
  ASSERT_TRUE(clean.ok()) << clean.message();
  double sum = 0.0;
  int count = 0;
  for (const auto& run : clean->residuals_rad) {
    for (double e : run) {
      if (std::abs(e) > std::sqrt(10.83) * clean->noise.bearing_sigma_rad) continue;
      sum += e * e;
      ++count;
    }
  }
  const double clean_rms = std::sqrt(sum / count);
  EXPECT_NEAR(d->baseline.rms_rad / clean_rms, 1.0, 0.05);
  double worst_bias = 0.0;
  const BearingParamVector base = ToVector(d->baseline.estimate);
  for (int i = 0; i < kNumBearingParams; ++i) {
    worst_bias =
        std::max(worst_bias, std::abs(ParamError(i, base(i), truth(i))) / d->baseline.stddev(i));
  }
  EXPECT_GE(worst_bias, 3.0);

  ASSERT_EQ(d->findings.size(), 1u);
  const BearingFinding& f = d->findings[0];
  EXPECT_TRUE(f.significant) << f.statement;
  ASSERT_EQ(d->adopted, std::vector<std::string>({"time_offset"}));
  EXPECT_LE(std::abs(f.value - kTimeOffset.time_offset_s), 3.0 * f.stddev)
      << f.value << " ± " << f.stddev;
  EXPECT_GT(f.concealment, 0.5);  // Most of it could hide in the base unknowns.
  const BearingParamVector after = ToVector(d->final_fit.estimate);
  for (int i = 0; i < kNumBearingParams; ++i) {
    EXPECT_LE(std::abs(ParamError(i, after(i), truth(i))), 2.0 * d->final_fit.stddev(i))
        << kBearingParamNames[i];
  }
  // The one-step shift predicts the refit's (to first order).
  for (int i = 0; i < kNumBearingParams; ++i) {
    EXPECT_NEAR(f.absorbed(i), f.base_shift(i), 0.5 * d->baseline.stddev(i))
        << kBearingParamNames[i];
  }
  EXPECT_GT(f.heldout_reduction, 0.0);
  EXPECT_EQ(f.location.covariate, "bearing_rate");
  EXPECT_NE(f.statement.find("stamped"), std::string::npos) << f.statement;
  EXPECT_NE(f.statement.find("early"), std::string::npos) << f.statement;
}

void ExpectNothingAdopted(const BearingLog& log) {
  const StatusOr<BearingDiagnosis> d = DiagnoseBearing(log);
  ASSERT_TRUE(d.ok()) << d.message();
  EXPECT_TRUE(d->adopted.empty()) << d->findings[0].statement;
  EXPECT_FALSE(d->findings[0].significant);
  EXPECT_FALSE(d->structure_before.found) << d->structure_before.statement;
}

TEST(BearingDiagnosisData, AdoptsNothingOnTheCleanControl) {
  ExpectNothingAdopted(ReadData(kClean.name));
}

TEST(BearingDiagnosisData, AdoptsNothingOnTheSampleCircles) {
  const StatusOr<BearingLog> log =
      ReadBearingLog((fs::path(CALIB_SOURCE_DIR) / "data" / "sample_bearing").string());
  ASSERT_TRUE(log.ok()) << log.message();
  ExpectNothingAdopted(*log);
}

// On constant-speed circles an offset only slides each run along its circle: the poses absorb
// it, the calibration stays unbiased, and the test says the log can barely see it.
TEST(BearingDiagnosisData, CirclesHideAnOffsetWithoutBias) {
  BearingSimOptions o;
  o.seed = 5;
  o.encoder_rate_hz = 5.0;
  o.bearing_noise_rad = M_PI / 180.0;
  o.initial_distance_run = 1;
  o.time_offset_s = 0.15;
  BearingSimTruth truth;
  const BearingLog log = SimulateBearingLog(o, &truth);
  const StatusOr<BearingDiagnosis> d = DiagnoseBearing(log);
  ASSERT_TRUE(d.ok()) << d.message();
  const BearingFinding& f = d->findings[0];
  EXPECT_GT(f.concealment, 0.9);
  EXPECT_GT(f.one_step_stddev(0), 0.05);  // Far less information than on the varying run.
  const BearingParamVector base = ToVector(d->baseline.estimate), t = ToVector(truth.params);
  for (int i = 0; i < kNumBearingParams; ++i) {
    EXPECT_LE(std::abs(ParamError(i, base(i), t(i))), 3.0 * d->baseline.stddev(i));
  }
}

}  // namespace
}  // namespace calib
