#ifndef CALIB_TESTS_SOLVERS_LASER_LASER_DIAGNOSIS_RECIPES_H_
#define CALIB_TESTS_SOLVERS_LASER_LASER_DIAGNOSIS_RECIPES_H_

#include <calib/core/laser/laser_simulator.h>
#include <calib/problems/laser/laser_effect_residual.h>
#include <calib/solvers/laser/laser_diagnosis.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

// The laser logs of data/diagnose: how each is made from the project's simulator, and the
// concealment it is meant to show (shared by the data tests and their generator).
namespace calib::testing {

// data/diagnose in the source tree.
std::filesystem::path DiagnoseDataDir();

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

std::vector<Recipe> Recipes();
std::vector<Recipe> ConcealedRecipes();  // Those with `concealed` set.
void PrintTo(const Recipe& recipe, std::ostream* os);

struct Generated {
  LaserLog log;
  LaserSimTruth truth;
  double speed_reference = 0.0;  // φ_ref of the speed-dependent radius.
};

// The recipe's log, or its clean counterpart (same seed and motion, no effects).
Generated Generate(const Recipe& recipe, bool with_effects);

// The concealment numbers of a recipe: the base fits of the log and of its clean counterpart.
struct Concealment {
  Eigen::Vector3d sigma_ratio;    // Inlier residual σ, log / clean, per component.
  LaserParamVector error_sigmas;  // (estimate − truth)/σ of the log's base fit.
  LaserParamVector shift_sigmas;  // (estimate − clean estimate)/σ.
};
Concealment MeasureConcealment(const Recipe& recipe);

nlohmann::json ReadJson(const std::filesystem::path& path);

}  // namespace calib::testing

#endif  // CALIB_TESTS_SOLVERS_LASER_LASER_DIAGNOSIS_RECIPES_H_
