#include "tests/solvers/laser/laser_diagnosis_recipes.h"

#include <calib/solvers/laser/calibrate_laser.h>
#include <gtest/gtest.h>

#include <fstream>
#include <utility>

#include "tests/problems/laser/laser_effect_gamma.h"

namespace calib::testing {

std::filesystem::path DiagnoseDataDir() {
  return std::filesystem::path(CALIB_SOURCE_DIR) / "data" / "diagnose";
}

namespace {

Recipe Make(const std::string& name, const LaserSimOptions& sim) {
  Recipe recipe;
  recipe.name = name;
  recipe.sim = sim;
  return recipe;
}

}  // namespace

// A table, one block per file of data/diagnose (longer than a screen for that reason alone).
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
    // The left wheel grows by 1.2 % at 700 s (inside the 1.5 % plausibility bound); a scan
    // matcher of 0.3 mm and 0.17°, so that the step stands as far above the noise as 4 % does
    // at 1 mm and 0.57°.
    Recipe r = Make("wheel_radius_change", cli);
    r.sim.seed = 6;
    r.sim.scan_noise_sigma = Eigen::Vector3d(0.0003, 0.0003, 0.003);
    r.sim.effects.radius_change_time_s = 700.0;
    r.sim.effects.left_radius_after_m = 0.020847;
    r.sim.effects.right_radius_after_m = 0.0207;
    r.effects = {LaserEffect::kWheelRadiusChange};
    r.concealed = true;
    r.cli =
        "--seed 6 --noise_xy 0.0003 --noise_theta 0.003 --radius_change_time 700 "
        "--r_l_after 0.020847 --r_r_after 0.0207";
    add(r);
  }
  {
    // Speeds constant within intervals, so that the speed-dependent radius is exact. 0.8 % per
    // 0.1 rad/s, inside the plausibility bound (1 %), and a scan matcher three times as precise
    // as elsewhere here: the effect's statistics scale with γ/σ.
    Recipe r = Make("speed_dependent_radius", cli);
    r.sim.seed = 6;
    r.sim.speed_time_constant_s = 0.0;
    r.sim.scan_noise_sigma = Eigen::Vector3d(0.00033, 0.00033, 0.0033);
    r.speed_radius = -0.08;
    r.effects = {LaserEffect::kSpeedDependentRadius};
    r.concealed = true;
    add(r);
  }
  {
    // Two effects: the radius change of wheel_radius_change and a 9 ms time offset (scaled
    // with the noise as the step is).
    Recipe r = Make("radius_change_and_time_offset", cli);
    r.sim.seed = 6;
    r.sim.scan_noise_sigma = Eigen::Vector3d(0.0003, 0.0003, 0.003);
    r.sim.effects.radius_change_time_s = 700.0;
    r.sim.effects.left_radius_after_m = 0.020847;
    r.sim.effects.right_radius_after_m = 0.0207;
    r.sim.effects.time_offset_s = 0.009;
    r.effects = {LaserEffect::kWheelRadiusChange, LaserEffect::kTimeOffset};
    r.concealed = true;
    r.cli =
        "--seed 6 --noise_xy 0.0003 --noise_theta 0.003 --radius_change_time 700 "
        "--r_l_after 0.020847 --r_r_after 0.0207 --time_offset 0.009";
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

nlohmann::json ReadJson(const std::filesystem::path& path) {
  std::ifstream in(path);
  nlohmann::json json;
  in >> json;
  return json;
}

}  // namespace calib::testing
