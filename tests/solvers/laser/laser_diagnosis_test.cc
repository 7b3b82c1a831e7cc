// `calib diagnose` for the laser problem: the candidate effects' residuals, the statistics, and
// the diagnosis on the concealed logs of data/diagnose and on the published recordings.
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/problems/laser/laser_effect_residual.h>
#include <calib/problems/laser/laser_residual.h>
#include <calib/solvers/laser/laser_diagnosis.h>
#include <calib/solvers/stats/change_point.h>
#include <calib/solvers/stats/score_test.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>

namespace calib {
namespace {

namespace fs = std::filesystem;

const fs::path kDataDir = fs::path(CALIB_SOURCE_DIR) / "data" / "diagnose";
const fs::path kCensiDir = CALIB_CENSI_DATA_DIR;

using EffectVector = Eigen::Matrix<double, kNumLaserEffectParams, 1>;

EffectVector Gamma(LaserEffect effect, double value, double second = 0.0) {
  EffectVector gamma = EffectVector::Zero();
  gamma(EffectInfo(effect).offset) = value;
  if (EffectInfo(effect).size > 1) gamma(EffectInfo(effect).offset + 1) = second;
  return gamma;
}

// A noise-free log with constant speeds per interval: the models are exact for it.
LaserSimOptions ExactOptions(int intervals, uint64_t seed) {
  LaserSimOptions sim;
  sim.num_intervals = intervals;
  sim.seed = seed;
  sim.speed_time_constant_s = 0.0;
  sim.segment_mean_s = 1.5;  // Frequent speed changes, where the boundary effects act.
  sim.scan_noise_sigma.setZero();
  return sim;
}

double MaxAbsResidual(const std::vector<LaserInterval>& intervals, const LaserSimOptions& sim,
                      const EffectVector& gamma, double change_time_s) {
  const std::vector<LaserEffectContext> contexts =
      BuildLaserEffectContexts(intervals, BoundarySpeedModel::kPiecewiseConstant, change_time_s);
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  const double odometry[3] = {sim.odometry.left_radius_m, sim.odometry.right_radius_m,
                              sim.odometry.wheelbase_m};
  const Pose2d& m = sim.base_T_sensor;
  const double mounting[3] = {m(0), m(1), m(2)};
  double worst = 0.0;
  for (const LaserEffectContext& context : contexts) {
    double residual[3];
    EXPECT_TRUE(
        LaserEffectResidual(context, &identity)(odometry, mounting, gamma.data(), residual));
    for (double r : residual) worst = std::max(worst, std::abs(r));
  }
  return worst;
}

// --- The effect residuals ------------------------------------------------------------------

TEST(LaserEffectResidualTest, EqualsTheBaseResidualAtZero) {
  LaserSimOptions sim = ExactOptions(300, 5);
  sim.scan_noise_sigma = Eigen::Vector3d(1e-3, 1e-3, 2e-3);
  sim.record_steps = 0;
  LaserLog log = SimulateLaserLog(sim);
  // Every other interval through the stepped (non-constant speed) model, as the base does.
  for (size_t k = 0; k < log.intervals.size(); k += 2) {
    LaserInterval& in = log.intervals[k];
    const double t = in.duration_s;
    in.steps = {{0.3 * t, 0.2 * in.left_speed * t, 0.5 * in.right_speed * t},
                {0.7 * t, 0.8 * in.left_speed * t, 0.5 * in.right_speed * t}};
  }
  const Eigen::Matrix3d sqrt_information = Eigen::Vector3d(1e3, 2e3, 5e2).asDiagonal();
  double odometry[3] = {0.021, 0.0205, 0.09};
  double mounting[3] = {0.01, -0.02, 0.7};
  double gamma[kNumLaserEffectParams] = {};
  for (BoundarySpeedModel model :
       {BoundarySpeedModel::kPiecewiseConstant, BoundarySpeedModel::kSmooth}) {
    // A change time inside the log: with γ = 0 it must not matter either.
    const std::vector<LaserEffectContext> contexts =
        BuildLaserEffectContexts(log.intervals, model, 100.3);
    for (size_t k = 0; k < contexts.size(); ++k) {
      std::unique_ptr<ceres::CostFunction> base(
          LaserResidual::Create(log.intervals[k], &sqrt_information));
      std::unique_ptr<ceres::CostFunction> effect(
          LaserEffectResidual::Create(contexts[k], &sqrt_information));
      double r_base[3], r_effect[3], j_base[2][9], j_effect[3][3 * kNumLaserEffectParams];
      double* base_parameters[2] = {odometry, mounting};
      double* effect_parameters[3] = {odometry, mounting, gamma};
      double* base_jacobians[2] = {j_base[0], j_base[1]};
      double* effect_jacobians[3] = {j_effect[0], j_effect[1], j_effect[2]};
      ASSERT_TRUE(base->Evaluate(base_parameters, r_base, base_jacobians));
      ASSERT_TRUE(effect->Evaluate(effect_parameters, r_effect, effect_jacobians));
      for (int i = 0; i < 3; ++i) EXPECT_EQ(r_base[i], r_effect[i]) << "interval " << k;
      for (int b = 0; b < 2; ++b) {
        for (int i = 0; i < 9; ++i) {
          EXPECT_NEAR(j_base[b][i], j_effect[b][i], 1e-12 * (1.0 + std::abs(j_base[b][i])))
              << "interval " << k << " block " << b << " entry " << i;
        }
      }
    }
  }
}

TEST(LaserEffectResidualTest, ZeroAtTheTruthOfEachSimulatedEffect) {
  struct Case {
    const char* name;
    LaserEffects effects;
    EffectVector gamma;
    double change_time_s = std::numeric_limits<double>::infinity();
  };
  const LaserSimOptions base = ExactOptions(600, 3);
  const OdometryParams& o = base.odometry;
  std::vector<Case> cases;
  for (double offset : {0.035, -0.025}) {
    Case c{"time_offset", {}, Gamma(LaserEffect::kTimeOffset, offset)};
    c.effects.time_offset_s = offset;
    cases.push_back(c);
  }
  {
    Case c{"lateral_slip", {}, Gamma(LaserEffect::kLateralSlip, 0.8)};
    c.effects.lateral_slip_s = 0.8;
    cases.push_back(c);
  }
  {
    Case c{"longitudinal_slip", {}, Gamma(LaserEffect::kLongitudinalSlip, 0.3)};
    c.effects.longitudinal_slip_s = 0.3;
    cases.push_back(c);
  }
  {
    const double after_l = o.left_radius_m * 1.02, after_r = o.right_radius_m * 0.99;
    Case c{"wheel_radius_change",
           {},
           Gamma(LaserEffect::kWheelRadiusChange, after_l / o.left_radius_m - 1.0,
                 after_r / o.right_radius_m - 1.0)};
    c.effects.radius_change_time_s = 203.7;  // Inside an interval.
    c.effects.left_radius_after_m = after_l;
    c.effects.right_radius_after_m = after_r;
    c.change_time_s = 203.7;
    cases.push_back(c);
  }
  for (const Case& c : cases) {
    LaserSimOptions sim = base;
    sim.effects = c.effects;
    const LaserLog log = SimulateLaserLog(sim);
    // The effect is visible to the base model...
    EXPECT_GT(MaxAbsResidual(log.intervals, sim, EffectVector::Zero(), c.change_time_s), 1e-5)
        << c.name;
    // ...and its model explains the simulation to rounding.
    EXPECT_LT(MaxAbsResidual(log.intervals, sim, c.gamma, c.change_time_s), 1e-12) << c.name;
  }
}

// The two omissions the data cannot see: exactly a change of the base parameters.
TEST(LaserEffectResidualTest, ConfoundedEffectsAreExactlyAbsorbed) {
  const LaserLog log = SimulateLaserLog(ExactOptions(200, 8));
  const std::vector<LaserEffectContext> contexts =
      BuildLaserEffectContexts(log.intervals, BoundarySpeedModel::kSmooth);
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  const double odometry[3] = {0.0206, 0.0207, 0.088};
  const double mounting[3] = {-0.005, 0.006, -1.55};
  const double offset = 0.013, scale = 0.02;
  // ICR at x = offset: the sensor seen from the no-slip point sits at x − offset.
  const double icr_mounting[3] = {mounting[0] - offset, mounting[1], mounting[2]};
  // Scan scale 1 + s: every length scaled by 1 + s.
  const double k = 1.0 + scale;
  const double scaled_odometry[3] = {odometry[0] * k, odometry[1] * k, odometry[2] * k};
  const double scaled_mounting[3] = {mounting[0] * k, mounting[1] * k, mounting[2]};
  const EffectVector zero = EffectVector::Zero();
  const EffectVector icr = Gamma(LaserEffect::kIcrOffset, offset);
  const EffectVector scan = Gamma(LaserEffect::kScanScale, scale);
  for (const LaserEffectContext& context : contexts) {
    double with_icr[3], base_icr[3], with_scale[3], base_scale[3];
    LaserEffectResidual(context, &identity)(odometry, mounting, icr.data(), with_icr);
    LaserEffectResidual(context, &identity)(odometry, icr_mounting, zero.data(), base_icr);
    LaserEffectResidual(context, &identity)(odometry, mounting, scan.data(), with_scale);
    LaserEffectResidual(context, &identity)(scaled_odometry, scaled_mounting, zero.data(),
                                            base_scale);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(with_icr[i], base_icr[i], 1e-15);
      EXPECT_NEAR(with_scale[i], base_scale[i], 1e-15);
    }
  }
}

TEST(LaserEffectResidualTest, JacobiansMatchCentralDifferences) {
  LaserSimOptions sim = ExactOptions(120, 21);
  sim.scan_noise_sigma = Eigen::Vector3d(1e-3, 1e-3, 2e-3);
  LaserLog log = SimulateLaserLog(sim);
  log.intervals[7].steps = {{0.3, 0.1, 0.2}, {0.5, -0.05, 0.3}};
  const Eigen::Matrix3d sqrt_information = Eigen::Vector3d(1e3, 1e3, 5e2).asDiagonal();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (BoundarySpeedModel model :
       {BoundarySpeedModel::kPiecewiseConstant, BoundarySpeedModel::kSmooth}) {
    const std::vector<LaserEffectContext> contexts =
        BuildLaserEffectContexts(log.intervals, model, log.intervals[40].start_s + 0.3);
    for (size_t k = 0; k < contexts.size(); k += 3) {
      std::vector<double> odometry = {0.021, 0.020, 0.09};
      std::vector<double> mounting = {0.01, -0.02, 0.3 * unit(rng)};
      // Away from γ = 0 (the time offset's kink) and with every effect on.
      std::vector<double> gamma = {0.02 + 0.01 * unit(rng), 0.5 * unit(rng),  0.2 * unit(rng),
                                   0.01 * unit(rng),        0.01 * unit(rng), 0.05 * unit(rng),
                                   0.01 * unit(rng),        0.01 * unit(rng), 0.01 * unit(rng)};
      std::vector<double>* blocks[3] = {&odometry, &mounting, &gamma};
      std::unique_ptr<ceres::CostFunction> cost(
          LaserEffectResidual::Create(contexts[k], &sqrt_information));
      double* parameters[3] = {odometry.data(), mounting.data(), gamma.data()};
      double residual[3];
      std::vector<std::vector<double>> jacobians = {std::vector<double>(9), std::vector<double>(9),
                                                    std::vector<double>(3 * kNumLaserEffectParams)};
      double* jacobian_ptrs[3] = {jacobians[0].data(), jacobians[1].data(), jacobians[2].data()};
      ASSERT_TRUE(cost->Evaluate(parameters, residual, jacobian_ptrs));
      for (int b = 0; b < 3; ++b) {
        const int size = static_cast<int>(blocks[b]->size());
        for (int i = 0; i < size; ++i) {
          double& x = (*blocks[b])[i];
          const double h = 1e-6 * std::max(1e-3, std::abs(x));
          const double saved = x;
          double plus[3], minus[3];
          x = saved + h;
          cost->Evaluate(parameters, plus, nullptr);
          x = saved - h;
          cost->Evaluate(parameters, minus, nullptr);
          x = saved;
          for (int r = 0; r < 3; ++r) {
            const double numeric = (plus[r] - minus[r]) / (2.0 * h);
            const double analytic = jacobians[b][r * size + i];
            EXPECT_NEAR(analytic, numeric, 1e-5 * (1.0 + std::abs(numeric)))
                << "interval " << k << " block " << b << " parameter " << i << " residual " << r;
          }
        }
      }
    }
  }
}

TEST(LaserEffectResidualTest, BoundarySpeedsFromPolynomialsAreExact) {
  // Cumulative angle Φ(t) = t³ − t: the 7-node derivative is exact for polynomials to degree 6.
  const std::vector<double> nodes = {0.0, 0.7, 1.5, 2.4, 3.1, 3.9, 4.8};
  const std::vector<double> weights = DerivativeWeights(nodes, 2.4);
  double derivative = 0.0;
  for (size_t j = 0; j < nodes.size(); ++j) {
    derivative += weights[j] * (std::pow(nodes[j], 3) - nodes[j]);
  }
  EXPECT_NEAR(derivative, 3 * 2.4 * 2.4 - 1.0, 1e-10);
  // At an isolated speed jump the smooth model takes the mean of the two sides.
  std::vector<LaserInterval> intervals(8);
  for (size_t k = 0; k < intervals.size(); ++k) {
    intervals[k].start_s = 0.8 * k;
    intervals[k].duration_s = 0.8;
    intervals[k].left_speed = intervals[k].right_speed = k < 4 ? 0.2 : 0.6;
  }
  const std::vector<LaserEffectContext> contexts =
      BuildLaserEffectContexts(intervals, BoundarySpeedModel::kSmooth);
  EXPECT_NEAR(contexts[4].start.before(0), 0.4, 1e-12);
  EXPECT_NEAR(contexts[4].start.after(1), 0.4, 1e-12);
  const std::vector<LaserEffectContext> piecewise =
      BuildLaserEffectContexts(intervals, BoundarySpeedModel::kPiecewiseConstant);
  EXPECT_EQ(piecewise[4].start.before(0), 0.2);
  EXPECT_EQ(piecewise[4].start.after(0), 0.6);
}

// --- The logs of data/diagnose ------------------------------------------------------------

// How a log of data/diagnose is made from the project's simulator.
struct Recipe {
  std::string name;                  // data/diagnose/<name>.tuple and <name>_truth.json.
  LaserSimOptions sim;               // With the effects.
  double speed_radius = 0.0;         // γ of the speed-dependent radius (applied after simulating).
  bool forward_only = false;         // Keep only intervals driving forward or turning on the spot.
  std::vector<LaserEffect> effects;  // What diagnose must adopt; empty for a control.
  bool concealed = false;  // Claims: residual σ within 5 % of the clean log's, a bias ≥ 3 σ.
  std::string cli;         // The same log from `calib simulate` ("" when the flags do not exist).
};

Recipe Make(const std::string& name, const LaserSimOptions& sim) {
  Recipe recipe;
  recipe.name = name;
  recipe.sim = sim;
  return recipe;
}

std::vector<Recipe> Recipes() {
  std::vector<Recipe> recipes;
  const auto add = [&](Recipe recipe) { recipes.push_back(std::move(recipe)); };
  LaserSimOptions cli;  // `calib simulate`'s defaults: smooth speeds, 2000 intervals.
  cli.num_intervals = 2000;
  {
    // Speeds commanded anew at (almost) every scan, constant in between: a time offset then
    // shrinks every interval's motion toward its neighbours' and hides in the wheel radii.
    Recipe r = Make("time_offset", cli);
    r.sim.seed = 4;
    r.sim.speed_time_constant_s = 0.0;
    r.sim.segment_mean_s = 0.8;
    r.sim.scan_noise_sigma = Eigen::Vector3d(0.001, 0.001, 0.01);
    r.sim.effects.time_offset_s = 0.03;
    r.effects = {LaserEffect::kTimeOffset};
    r.concealed = true;
    add(r);
  }
  {
    // A faster robot that drives forward only (and turns on the spot): a lateral slip in arcs
    // looks like a shifted sensor x.
    Recipe r = Make("lateral_slip", cli);
    r.sim.seed = 1;
    r.sim.num_intervals = 4000;
    r.sim.max_wheel_speed = 4.0;
    r.sim.effects.lateral_slip_s = 0.04;
    r.forward_only = true;
    r.effects = {LaserEffect::kLateralSlip};
    r.concealed = true;
    add(r);
  }
  {
    // Not concealable (see README): hidden in the noise level, it biases nothing.
    Recipe r = Make("longitudinal_slip", cli);
    r.sim.seed = 4;
    r.sim.effects.longitudinal_slip_s = 0.2;
    r.effects = {LaserEffect::kLongitudinalSlip};
    r.cli = "--seed 4 --longitudinal_slip 0.2";
    add(r);
  }
  {
    // The left wheel grows by 4 % at 700 s; a realistic angular scan noise of 0.57°.
    Recipe r = Make("wheel_radius_change", cli);
    r.sim.seed = 6;
    r.sim.scan_noise_sigma = Eigen::Vector3d(0.001, 0.001, 0.01);
    r.sim.effects.radius_change_time_s = 700.0;
    r.sim.effects.left_radius_after_m = 0.021424;
    r.sim.effects.right_radius_after_m = 0.0207;
    r.effects = {LaserEffect::kWheelRadiusChange};
    r.concealed = true;
    r.cli =
        "--seed 6 --noise_theta 0.01 --radius_change_time 700 --r_l_after 0.021424 "
        "--r_r_after 0.0207";
    add(r);
  }
  {
    // Speeds constant within intervals, so that the speed-dependent radius is exact.
    Recipe r = Make("speed_dependent_radius", cli);
    r.sim.seed = 6;
    r.sim.speed_time_constant_s = 0.0;
    r.sim.scan_noise_sigma = Eigen::Vector3d(0.001, 0.001, 0.01);
    r.speed_radius = -0.25;
    r.effects = {LaserEffect::kSpeedDependentRadius};
    r.concealed = true;
    add(r);
  }
  {
    // Two effects: the radius change of wheel_radius_change and a 30 ms time offset.
    Recipe r = Make("radius_change_and_time_offset", cli);
    r.sim.seed = 6;
    r.sim.scan_noise_sigma = Eigen::Vector3d(0.001, 0.001, 0.01);
    r.sim.effects.radius_change_time_s = 700.0;
    r.sim.effects.left_radius_after_m = 0.021424;
    r.sim.effects.right_radius_after_m = 0.0207;
    r.sim.effects.time_offset_s = 0.03;
    r.effects = {LaserEffect::kWheelRadiusChange, LaserEffect::kTimeOffset};
    r.concealed = true;
    r.cli =
        "--seed 6 --noise_theta 0.01 --radius_change_time 700 --r_l_after 0.021424 "
        "--r_r_after 0.0207 --time_offset 0.03";
    add(r);
  }
  {
    Recipe r = Make("clean", cli);
    r.sim.seed = 7;
    r.cli = "--seed 7";
    add(r);
  }
  {
    Recipe r = Make("clean_outliers", cli);
    r.sim.seed = 8;
    r.sim.outlier_fraction = 0.05;
    r.cli = "--seed 8 --outliers 0.05";
    add(r);
  }
  {
    // The regime of time_offset (speeds constant within intervals, frequent changes).
    Recipe r = Make("clean_piecewise_outliers", cli);
    r.sim.seed = 9;
    r.sim.speed_time_constant_s = 0.0;
    r.sim.segment_mean_s = 0.8;
    r.sim.scan_noise_sigma = Eigen::Vector3d(0.001, 0.001, 0.01);
    r.sim.outlier_fraction = 0.05;
    add(r);
  }
  return recipes;
}

void PrintTo(const Recipe& recipe, std::ostream* os) { *os << recipe.name; }

std::vector<Recipe> ConcealedRecipes() {
  std::vector<Recipe> concealed;
  for (const Recipe& recipe : Recipes()) {
    if (recipe.concealed) concealed.push_back(recipe);
  }
  return concealed;
}

struct Generated {
  LaserLog log;
  LaserSimTruth truth;
  double speed_reference = 0.0;  // φ_ref of the speed-dependent radius.
};

// The recipe's log, or its clean counterpart (same seed and motion, no effects).
Generated Generate(const Recipe& recipe, bool with_effects) {
  Generated out;
  LaserSimOptions sim = recipe.sim;
  if (!with_effects) sim.effects = LaserEffects();
  out.log = SimulateLaserLog(sim, &out.truth);
  std::vector<LaserInterval>& intervals = out.log.intervals;
  const std::vector<LaserEffectContext> contexts =
      BuildLaserEffectContexts(intervals, BoundarySpeedModel::kPiecewiseConstant);
  out.speed_reference = contexts.empty() ? 0.0 : contexts[0].reference_speed;
  if (with_effects && recipe.speed_radius != 0.0) {
    // Exact for speeds constant within intervals: the sensor motion of the effect's robot
    // motion, keeping the simulated scan noise (sm = ŝ + noise).
    const double odometry[3] = {sim.odometry.left_radius_m, sim.odometry.right_radius_m,
                                sim.odometry.wheelbase_m};
    const EffectVector gamma = Gamma(LaserEffect::kSpeedDependentRadius, recipe.speed_radius);
    const EffectVector zero = EffectVector::Zero();
    for (size_t k = 0; k < intervals.size(); ++k) {
      const Pose2d with = SensorMotionFromRobotMotion(
          sim.base_T_sensor, EffectRobotMotion(odometry, gamma.data(), contexts[k]));
      const Pose2d without = SensorMotionFromRobotMotion(
          sim.base_T_sensor, EffectRobotMotion(odometry, zero.data(), contexts[k]));
      intervals[k].sensor_motion += with - without;
    }
  }
  if (recipe.forward_only) {
    intervals = DropBackwardIntervals(intervals, sim.odometry);
    if (intervals.size() > 2000) intervals.resize(2000);  // data/diagnose files stay small.
  }
  for (size_t k = 0; k < intervals.size(); ++k) intervals[k].record = static_cast<int>(k + 1);
  return out;
}

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

// The concealment numbers of a recipe: the base fits of the log and of its clean counterpart.
struct Concealment {
  Eigen::Vector3d sigma_ratio;    // Inlier residual σ, log / clean, per component.
  LaserParamVector error_sigmas;  // (estimate − truth)/σ of the log's base fit.
  LaserParamVector shift_sigmas;  // (estimate − clean estimate)/σ.
};
Concealment MeasureConcealment(const Recipe& recipe) {
  const Generated with = Generate(recipe, true), without = Generate(recipe, false);
  const StatusOr<LaserCalibrationResult> a = CalibrateLaser(with.log.intervals);
  const StatusOr<LaserCalibrationResult> b = CalibrateLaser(without.log.intervals);
  Concealment c;
  if (!a.ok() || !b.ok()) {
    ADD_FAILURE() << recipe.name << ": " << (a.ok() ? b.message() : a.message());
    return c;
  }
  c.sigma_ratio = a->noise_sigma[0].cwiseQuotient(b->noise_sigma[0]);
  const LaserCalibration truth{with.truth.odometry, with.truth.base_T_sensor};
  c.error_sigmas = (a->estimate.ToVector() - truth.ToVector()).cwiseQuotient(a->stddev);
  c.shift_sigmas = (a->estimate.ToVector() - b->estimate.ToVector()).cwiseQuotient(a->stddev);
  return c;
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

nlohmann::json ReadJson(const fs::path& path) {
  std::ifstream in(path);
  nlohmann::json json;
  in >> json;
  return json;
}

class DataLogTest : public ::testing::TestWithParam<Recipe> {};

// The files are what their recipes make (so that the README's commands reproduce them).
TEST_P(DataLogTest, FileMatchesItsRecipe) {
  const Recipe& recipe = GetParam();
  const StatusOr<LaserLog> file = ReadLaserLog((kDataDir / (recipe.name + ".tuple")).string());
  ASSERT_TRUE(file.ok()) << file.message();
  const Generated generated = Generate(recipe, true);
  ASSERT_EQ(file->intervals.size(), generated.log.intervals.size());
  for (size_t k = 0; k < file->intervals.size(); ++k) {
    const LaserInterval& a = file->intervals[k];
    const LaserInterval& b = generated.log.intervals[k];
    ASSERT_EQ(a.duration_s, b.duration_s) << k;
    ASSERT_EQ(a.left_speed, b.left_speed) << k;
    ASSERT_EQ(a.right_speed, b.right_speed) << k;
    ASSERT_EQ(a.sensor_motion, b.sensor_motion) << k;
    ASSERT_EQ(a.gap_before, b.gap_before) << k;
  }
  EXPECT_LE(file->intervals.size(), 2000u);
}

// The "concealed": the base fit's residual σ within 5 % of that of the same log without
// the effect, while some base parameter is ≥ 3 σ from the truth.
class ConcealedLogTest : public ::testing::TestWithParam<Recipe> {};

TEST_P(ConcealedLogTest, HidesItsEffect) {
  const Recipe& recipe = GetParam();
  const Concealment c = MeasureConcealment(recipe);
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(c.sigma_ratio(j), 1.0, 0.05) << recipe.name << " component " << j;
  }
  EXPECT_GE(c.error_sigmas.cwiseAbs().maxCoeff(), 3.0)
      << recipe.name << ": " << c.error_sigmas.transpose();
}

// Diagnose names the right effects, estimates them within 3 σ of the truth, brings the
// parameters the base fit had biased by ≥ 3 σ back within 2 σ, adopts nothing on the controls,
// and flags the two confounded candidates without ever adopting them.
TEST_P(DataLogTest, DiagnoseFindsTheEffect) {
  const Recipe& recipe = GetParam();
  const StatusOr<LaserLog> log = ReadLaserLog((kDataDir / (recipe.name + ".tuple")).string());
  ASSERT_TRUE(log.ok()) << log.message();
  const nlohmann::json truth = ReadJson(kDataDir / (recipe.name + "_truth.json"));
  const StatusOr<LaserDiagnosis> d = DiagnoseLaser(log->intervals, LaserDiagnosisOptions());
  ASSERT_TRUE(d.ok()) << d.message();

  std::vector<std::string> adopted, expected;
  for (LaserEffect e : d->adopted) adopted.push_back(LaserEffectName(e));
  for (const auto& e : truth["expected_effects"]) expected.push_back(e.get<std::string>());
  std::sort(adopted.begin(), adopted.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(adopted, expected) << recipe.name;
  EXPECT_EQ(d->final_fit.effects.size(), d->adopted.size());

  for (const LaserFinding& f : d->findings) {
    if (f.effect == LaserEffect::kIcrOffset || f.effect == LaserEffect::kScanScale) {
      EXPECT_TRUE(f.confounded) << f.name;
      EXPECT_FALSE(f.significant) << f.name;
      EXPECT_FALSE(f.confounded_with.empty()) << f.name;
      const auto has = [&](const char* name) {
        return std::find(f.confounded_with.begin(), f.confounded_with.end(), name) !=
               f.confounded_with.end();
      };
      if (f.effect == LaserEffect::kIcrOffset) {
        EXPECT_EQ(f.confounded_with, std::vector<std::string>{"sensor_x"});
      } else {
        EXPECT_TRUE(has("r_l") && has("r_r") && has("b"))
            << testing::PrintToString(f.confounded_with);
      }
      continue;
    }
    if (!f.significant) continue;
    const nlohmann::json& effects = truth["effects"];
    std::vector<std::pair<double, double>> checks;  // (estimate − truth, σ)
    if (f.effect == LaserEffect::kWheelRadiusChange) {
      checks.push_back({f.value - effects["wheel_radius_change"].get<double>(), f.stddev});
      checks.push_back({f.r_l_after - effects["r_l_after"].get<double>(), f.r_l_after_stddev});
      checks.push_back({f.r_r_after - effects["r_r_after"].get<double>(), f.r_r_after_stddev});
    } else {
      checks.push_back({f.value - effects[f.name].get<double>(), f.stddev});
    }
    for (const auto& [error, sigma] : checks) {
      EXPECT_GT(sigma, 0.0) << f.name;
      EXPECT_LT(std::abs(error), 3.0 * sigma)
          << recipe.name << ": " << f.name << " off by " << error << ", σ " << sigma;
    }
  }
  const nlohmann::json& estimate = truth["estimate"];
  for (int i = 0; i < kNumLaserParams; ++i) {
    const double true_value = estimate[kLaserParamNames[i]].get<double>();
    const double before = (d->baseline.estimate.ToVector()(i) - true_value) / d->baseline.stddev(i);
    const double after =
        (d->final_fit.estimate.ToVector()(i) - true_value) / d->final_fit.stddev(i);
    if (std::abs(before) >= 3.0) {
      EXPECT_LT(std::abs(after), 2.0) << recipe.name << ": " << kLaserParamNames[i] << " was "
                                      << before << " σ off, is " << after << " σ off";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(DataDiagnose, DataLogTest, ::testing::ValuesIn(Recipes()),
                         [](const ::testing::TestParamInfo<Recipe>& info) {
                           return info.param.name;
                         });
INSTANTIATE_TEST_SUITE_P(DataDiagnose, ConcealedLogTest, ::testing::ValuesIn(ConcealedRecipes()),
                         [](const ::testing::TestParamInfo<Recipe>& info) {
                           return info.param.name;
                         });

// `calib diagnose` writes the contract's keys and the plots (skips without the binary).
TEST(LaserDiagnoseCliTest, WritesTheContractJsonAndPlots) {
  const fs::path binary = fs::path(CALIB_BINARY_DIR) / "bin" / "calib";
  if (!fs::exists(binary)) GTEST_SKIP() << binary << " is not built";
  const fs::path out = fs::temp_directory_path() / "calib_diagnose_test";
  fs::remove_all(out);
  fs::create_directories(out);
  const std::string command = binary.string() + " diagnose --quiet --input " +
                              (kDataDir / "time_offset.tuple").string() + " --output " +
                              (out / "result.json").string();
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const nlohmann::json json = ReadJson(out / "result.json");
  ASSERT_TRUE(json.contains("baseline") && json.contains("findings") && json.contains("final"));
  EXPECT_TRUE(json["baseline"]["estimate"].contains("sensor_theta"));
  EXPECT_EQ(json["baseline"]["rms"].size(), 3u);
  EXPECT_EQ(json["final"]["effects"], nlohmann::json::array({"time_offset"}));
  bool found = false;
  for (const auto& f : json["findings"]) {
    for (const char* key : {"effect", "significant", "value", "stddev", "unit", "statement"}) {
      EXPECT_TRUE(f.contains(key)) << key;
    }
    if (f["effect"] == "time_offset") {
      found = true;
      EXPECT_TRUE(f["significant"].get<bool>());
      EXPECT_EQ(f["unit"], "s");
      ASSERT_TRUE(f.contains("plot"));
      EXPECT_TRUE(fs::exists(f["plot"].get<std::string>()));
    }
    if (f["effect"] == "icr_offset_x") {
      EXPECT_FALSE(f["significant"].get<bool>());
      EXPECT_EQ(f["confounded_with"], nlohmann::json::array({"sensor_x"}));
    }
  }
  EXPECT_TRUE(found);
  EXPECT_TRUE(fs::exists(out / "result_plots" / "residuals_vs_time.svg"));
  // An unreadable log: a message naming the file, a non-zero status.
  const std::string bad = binary.string() + " diagnose --quiet --input " +
                          (out / "missing.tuple").string() + " --output " +
                          (out / "x.json").string() + " 2>/dev/null";
  EXPECT_NE(std::system(bad.c_str()), 0);
}

// --- The published recordings, with a known effect injected --------------------------------

class CensiInjectionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kCensiDir / "l90.tuple")) {
      GTEST_SKIP() << "the published recordings are not at " << kCensiDir
                   << " (they are not part of the repository)";
    }
    const StatusOr<LaserLog> log = ReadLaserLog((kCensiDir / "l90.tuple").string());
    ASSERT_TRUE(log.ok()) << log.message();
    intervals_ = log->intervals;
  }

  // The one-effect diagnosis; returns the finding.
  LaserFinding Diagnose(const std::vector<LaserInterval>& intervals, LaserEffect effect) {
    LaserDiagnosisOptions options;
    options.candidates = {effect};
    const StatusOr<LaserDiagnosis> d = DiagnoseLaser(intervals, options);
    EXPECT_TRUE(d.ok()) << d.message();
    for (const LaserFinding& f : d->findings) {
      if (f.effect == effect) return f;
    }
    ADD_FAILURE() << "no finding for " << LaserEffectName(effect);
    return LaserFinding();
  }

  std::vector<LaserInterval> intervals_;
};

// Re-mixing neighbouring wheel speeds, φ'_k = (1 − a)·φ_k + a·φ_{k+1}, makes interval k's wheels
// those of [t_k + a·T, t_{k+1} + a·T]: the scans now run a·T early, a time offset of −a·T.
TEST_F(CensiInjectionTest, InjectedTimeShiftIsFound) {
  const double a = 0.1;
  std::vector<LaserInterval> shifted = intervals_;
  double sum_t = 0.0;
  for (size_t k = 0; k + 1 < shifted.size(); ++k) {
    shifted[k].left_speed = (1 - a) * intervals_[k].left_speed + a * intervals_[k + 1].left_speed;
    shifted[k].right_speed =
        (1 - a) * intervals_[k].right_speed + a * intervals_[k + 1].right_speed;
    sum_t += intervals_[k].duration_s;
  }
  const double injected = -a * sum_t / (shifted.size() - 1);
  const LaserFinding before = Diagnose(intervals_, LaserEffect::kTimeOffset);
  const LaserFinding after = Diagnose(shifted, LaserEffect::kTimeOffset);
  EXPECT_TRUE(after.significant);
  EXPECT_GT(after.statistic, before.statistic);
  const double change = after.value - before.value;
  EXPECT_LT(std::abs(change - injected), 3.0 * std::hypot(before.stddev, after.stddev))
      << "injected " << injected << " s, found " << before.value << " → " << after.value;
}

// A lateral slip added to sm through the model at the base calibration.
TEST_F(CensiInjectionTest, InjectedLateralSlipIsFound) {
  const double injected = 0.3;  // s: lateral velocity 0.3·v·ω.
  const StatusOr<LaserCalibrationResult> base = CalibrateLaser(intervals_);
  ASSERT_TRUE(base.ok());
  const LaserParamVector v = base->estimate.ToVector();
  const std::vector<LaserEffectContext> contexts =
      BuildLaserEffectContexts(intervals_, BoundarySpeedModel::kSmooth);
  const EffectVector gamma = Gamma(LaserEffect::kLateralSlip, injected);
  const EffectVector zero = EffectVector::Zero();
  const Pose2d mounting(v(3), v(4), v(5));
  std::vector<LaserInterval> slipped = intervals_;
  for (size_t k = 0; k < slipped.size(); ++k) {
    slipped[k].sensor_motion +=
        SensorMotionFromRobotMotion(mounting,
                                    EffectRobotMotion(v.data(), gamma.data(), contexts[k])) -
        SensorMotionFromRobotMotion(mounting,
                                    EffectRobotMotion(v.data(), zero.data(), contexts[k]));
  }
  const LaserFinding before = Diagnose(intervals_, LaserEffect::kLateralSlip);
  const LaserFinding after = Diagnose(slipped, LaserEffect::kLateralSlip);
  EXPECT_TRUE(after.significant);
  const double change = after.value - before.value;
  EXPECT_LT(std::abs(change - injected), 3.0 * std::hypot(before.stddev, after.stddev))
      << "injected " << injected << " s, found " << before.value << " → " << after.value;
}

}  // namespace
}  // namespace calib
