// `calib diagnose` for the bearing problem: the time-offset residual, its score test, and the
// diagnosis on the concealed bearing log of data/diagnose and on controls.
#include <calib/core/bearing/bearing_log_io.h>
#include <calib/core/bearing/bearing_simulator.h>
#include <calib/problems/bearing/bearing_observation_residual.h>
#include <calib/problems/bearing/bearing_time_offset_residual.h>
#include <calib/solvers/bearing/bearing_diagnosis.h>
#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace calib {
namespace {

namespace fs = std::filesystem;

const fs::path kDataDir = fs::path(CALIB_SOURCE_DIR) / "data" / "diagnose";

// How the bearing logs of data/diagnose are made. One run of 300 s at a constant nominal speed
// (5 cm/s) whose turn rate swings as 0.18·sin(2πt/80 s) rad/s; encoders at 5 Hz (K = 1e-3),
// bearings at 2 Hz (σβ = 1°), Martinelli's Table 2 calibration, the landmark 1 m to the left of
// the start (its distance given). At constant speed the offset's along-track part is exactly a
// forward shift of the sensor (φ, η absorb it), and its heading part τ·ω varies slowly enough for
// the poses to follow: concealed.
struct BearingRecipe {
  std::string name;
  double time_offset_s = 0.0;
  uint64_t seed = 1;
};

BearingSimOptions RecipeOptions(const BearingRecipe& recipe) {
  BearingSimOptions o;
  o.seed = recipe.seed;
  o.encoder_rate_hz = 5.0;
  o.bearing_rate_hz = 2.0;
  o.bearing_noise_rad = M_PI / 180.0;
  o.encoder_noise_k = 1e-3;
  o.initial_distance_run = 1;
  o.time_offset_s = recipe.time_offset_s;
  o.runs = {WeavingRun()};
  return o;
}

const BearingRecipe kTimeOffset{"bearing_time_offset", 0.15, 1};
const BearingRecipe kClean{"bearing_clean", 0.0, 2};

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

// --- Model ----------------------------------------------------------------------------------

BearingLog ExactLog(double time_offset_s) {
  BearingSimOptions o = RecipeOptions({"exact", time_offset_s, 3});
  o.encoder_noise_k = 0.0;
  o.bearing_noise_rad = 0.0;
  o.runs[0].duration_s = 60.0;
  return SimulateBearingLog(o);
}

TEST(BearingTimeOffsetModel, IntegrationDifferentiatesTheEndTime) {
  const BearingLog log = ExactLog(0.0);
  const std::vector<EncoderSample>& odometry = log.runs[0].odometry;
  using Jet = ceres::Jet<double, 1>;
  for (double t1 : {10.05, 10.13, 33.33}) {  // Off the samples (a kink there).
    const Pose2<Jet> jet = IntegrateEncoders(odometry, Jet(10.0), Jet(t1, 0), 0.3, 0.5, Jet(1.0),
                                             Jet(1.01), Jet(0.97));
    const Pose2d value = IntegrateEncoders(odometry, 10.0, t1, 0.3, 0.5, 1.0, 1.01, 0.97);
    const double h = 1e-6;
    const Pose2d plus = IntegrateEncoders(odometry, 10.0, t1 + h, 0.3, 0.5, 1.0, 1.01, 0.97);
    const Pose2d minus = IntegrateEncoders(odometry, 10.0, t1 - h, 0.3, 0.5, 1.0, 1.01, 0.97);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(jet(i).a, value(i), 1e-14);
      EXPECT_NEAR(jet(i).v[0], (plus(i) - minus(i)) / (2.0 * h), 1e-7) << t1 << " " << i;
    }
  }
}

TEST(BearingTimeOffsetModel, ReducesToTheBaseAtZeroAndIsExactAtTheTruth) {
  const double tau = 0.15;
  BearingSimTruth truth;
  BearingSimOptions o = RecipeOptions({"exact", tau, 3});
  o.encoder_noise_k = 0.0;
  o.bearing_noise_rad = 0.0;
  o.runs[0].duration_s = 60.0;
  const BearingLog log = SimulateBearingLog(o, &truth);
  const BearingRun& run = log.runs[0];
  const BearingParamVector c = ToVector(truth.params);
  const double one = 1.0;
  // Gauge δR ≡ 1: lengths in δR metres.
  const double scale = 1.0 / truth.metric.delta_r;
  double max_at_truth = 0.0, max_without = 0.0;
  for (size_t j = 1; j + 1 < run.bearings.size(); ++j) {
    const BearingSample& b = run.bearings[j];
    // The true pose at the stamp: dead reckoning of the exact encoders from the start.
    const Pose2d start = truth.runs[0].world_T_robot_start;
    Pose2d at_stamp =
        Compose(Pose2d(start(0) * scale, start(1) * scale, start(2)),
                IntegrateEncoders(run.odometry, run.odometry.front().t_s, b.t_s, 0.3, 0.5, 1.0,
                                  c(kBearingDelta), 1.0 / (0.5 * c(kBearingXi))));
    const BearingTimeOffsetResidual model(b.bearing_rad, b.t_s, &run.odometry, 0.3, 0.5, &one);
    const double zero = 0.0;
    // At τ = 0 it is the base term exactly.
    EXPECT_EQ(model.Error(at_stamp.data(), c.data(), &zero),
              BearingObservationResidual::Error(b.bearing_rad, at_stamp.data(), c.data()));
    max_at_truth = std::max(max_at_truth, std::abs(model.Error(at_stamp.data(), c.data(), &tau)));
    max_without = std::max(max_without, std::abs(model.Error(at_stamp.data(), c.data(), &zero)));
  }
  EXPECT_LT(max_at_truth, 1e-9);
  EXPECT_GT(max_without, 1e-3);  // The offset is visible at the true poses.
}

TEST(BearingTimeOffsetModel, JacobianMatchesNumericDifferences) {
  const BearingLog log = ExactLog(0.0);
  const BearingRun& run = log.runs[0];
  const double inverse_sigma = 50.0;
  const BearingSample& b = run.bearings[37];
  std::unique_ptr<ceres::CostFunction> cost(BearingTimeOffsetResidual::Create(
      b.bearing_rad, b.t_s, &run.odometry, 0.3, 0.5, &inverse_sigma));
  double pose[3] = {0.3, -0.8, 0.4};
  double c[kNumBearingParams] = {0.05, 1.5, 1.6, 1.01, 2.0};
  double tau[1] = {0.07};
  double* blocks[3] = {pose, c, tau};
  double residual = 0.0;
  double j_pose[3], j_c[kNumBearingParams], j_tau[1];
  double* jacobians[3] = {j_pose, j_c, j_tau};
  ASSERT_TRUE(cost->Evaluate(blocks, &residual, jacobians));
  const int sizes[3] = {3, kNumBearingParams, 1};
  double* analytic[3] = {j_pose, j_c, j_tau};
  for (int block = 0; block < 3; ++block) {
    for (int k = 0; k < sizes[block]; ++k) {
      const double h = 1e-6, saved = blocks[block][k];
      double plus = 0.0, minus = 0.0;
      blocks[block][k] = saved + h;
      cost->Evaluate(blocks, &plus, nullptr);
      blocks[block][k] = saved - h;
      cost->Evaluate(blocks, &minus, nullptr);
      blocks[block][k] = saved;
      EXPECT_NEAR(analytic[block][k], (plus - minus) / (2.0 * h),
                  1e-5 * std::max(1.0, std::abs(analytic[block][k])))
          << "block " << block << " entry " << k;
    }
  }
}

// A stamp exactly on an encoder sample, where the wheel speeds jump: ∂r/∂τ at τ = 0 is the mean
// of the two one-sided derivatives (the central difference), not the later step's alone.
TEST(BearingTimeOffsetModel, SensitivityIsTwoSidedOnAnEncoderSample) {
  std::vector<EncoderSample> odometry;
  for (int k = 0; k <= 4; ++k) {
    const double t = 0.5 * k;
    // Left 1 rad/s, right 2 rad/s until t = 1 s; then left 3 rad/s, right 1 rad/s.
    const double before = std::min(t, 1.0), after = std::max(t - 1.0, 0.0);
    odometry.push_back({t, before + 3.0 * after, 2.0 * before + after, k + 1});
  }
  const double t_stamp = odometry[2].t_s;
  using Jet = ceres::Jet<double, 1>;
  const Pose2<Jet> jet = IntegrateEncoders(odometry, Jet(t_stamp), Jet(t_stamp, 0), 0.3, 0.5,
                                           Jet(1.0), Jet(1.01), Jet(0.97));
  const double h = 1e-6;
  const Pose2d plus = IntegrateEncoders(odometry, t_stamp, t_stamp + h, 0.3, 0.5, 1.0, 1.01, 0.97);
  const Pose2d minus = IntegrateEncoders(odometry, t_stamp, t_stamp - h, 0.3, 0.5, 1.0, 1.01, 0.97);
  for (int i = 0; i < 3; ++i) {  // O(h) error: the curvature differs on the two sides.
    EXPECT_NEAR(jet(i).v[0], (plus(i) - minus(i)) / (2.0 * h), 1e-5) << i;
  }
  EXPECT_GT(std::abs(jet(2).v[0]), 0.1);  // The heading moves: the test has a kink to see.

  const double inverse_sigma = 50.0;
  std::unique_ptr<ceres::CostFunction> cost(
      BearingTimeOffsetResidual::Create(0.7, t_stamp, &odometry, 0.3, 0.5, &inverse_sigma));
  double pose[3] = {0.3, -0.8, 0.4};
  double c[kNumBearingParams] = {0.05, 1.5, 1.6, 1.01, 2.0};
  double tau[1] = {0.0};
  double* blocks[3] = {pose, c, tau};
  double residual = 0.0, r_plus = 0.0, r_minus = 0.0;
  double j_pose[3], j_c[kNumBearingParams], j_tau[1];
  double* jacobians[3] = {j_pose, j_c, j_tau};
  ASSERT_TRUE(cost->Evaluate(blocks, &residual, jacobians));
  tau[0] = h;
  cost->Evaluate(blocks, &r_plus, nullptr);
  tau[0] = -h;
  cost->Evaluate(blocks, &r_minus, nullptr);
  EXPECT_NEAR(j_tau[0], (r_plus - r_minus) / (2.0 * h), 1e-5 * std::max(1.0, std::abs(j_tau[0])));
}

// --- The logs of data/diagnose --------------------------------------------------------------

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

// `calib diagnose` on a bearing directory writes the contract's keys and the plots.
TEST(BearingDiagnoseCliTest, WritesTheContractJsonAndPlots) {
  const fs::path binary = fs::path(CALIB_BINARY_DIR) / "bin" / "calib";
  if (!fs::exists(binary)) GTEST_SKIP() << binary << " is not built";
  const fs::path out = fs::temp_directory_path() / "calib_bearing_diagnose_test";
  fs::remove_all(out);
  fs::create_directories(out);
  const std::string command = binary.string() + " diagnose --quiet --input " +
                              (kDataDir / kTimeOffset.name).string() + " --output " +
                              (out / "result.json").string();
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  std::ifstream in(out / "result.json");
  const nlohmann::json json = nlohmann::json::parse(in);
  EXPECT_EQ(json["problem"], "bearing");
  ASSERT_TRUE(json.contains("baseline") && json.contains("findings") && json.contains("final"));
  for (const char* name : {"phi", "psi", "eta", "delta", "xi", "rho", "delta_r"}) {
    EXPECT_TRUE(json["baseline"]["estimate"].contains(name)) << name;
    EXPECT_TRUE(json["final"]["estimate"].contains(name)) << name;
  }
  EXPECT_EQ(json["baseline"]["rms"].size(), 1u);
  EXPECT_EQ(json["final"]["effects"], nlohmann::json::array({"time_offset"}));
  ASSERT_EQ(json["findings"].size(), 1u);
  const nlohmann::json& f = json["findings"][0];
  for (const char* key : {"effect", "significant", "value", "stddev", "unit", "statement"}) {
    EXPECT_TRUE(f.contains(key)) << key;
  }
  EXPECT_EQ(f["effect"], "time_offset");
  EXPECT_TRUE(f["significant"].get<bool>());
  EXPECT_EQ(f["unit"], "s");
  ASSERT_TRUE(f.contains("plot"));
  EXPECT_TRUE(fs::exists(f["plot"].get<std::string>()));
  EXPECT_TRUE(fs::exists(out / "result_plots" / "residuals_vs_time.svg"));
  // A directory with a broken bearings.csv: a message naming the file, a non-zero status.
  fs::create_directories(out / "broken");
  for (const char* name : {"odometry.csv", "meta.json"}) {
    fs::copy_file(kDataDir / kTimeOffset.name / name, out / "broken" / name);
  }
  std::ofstream(out / "broken" / "bearings.csv") << "run,t,bearing\n1,0,nan\n";
  const std::string bad = binary.string() + " diagnose --quiet --input " +
                          (out / "broken").string() + " --output " + (out / "x.json").string() +
                          " 2>" + (out / "err.txt").string();
  EXPECT_NE(std::system(bad.c_str()), 0);
  std::ifstream err(out / "err.txt");
  const std::string message((std::istreambuf_iterator<char>(err)),
                            std::istreambuf_iterator<char>());
  EXPECT_NE(message.find("bearings.csv"), std::string::npos) << message;
}

}  // namespace
}  // namespace calib
