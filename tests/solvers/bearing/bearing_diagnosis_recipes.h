#ifndef CALIB_TESTS_SOLVERS_BEARING_BEARING_DIAGNOSIS_RECIPES_H_
#define CALIB_TESTS_SOLVERS_BEARING_BEARING_DIAGNOSIS_RECIPES_H_

#include <calib/core/bearing/bearing_simulator.h>

#include <cmath>
#include <cstdint>
#include <string>

namespace calib::testing {

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

inline BearingSimOptions RecipeOptions(const BearingRecipe& recipe) {
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

inline const BearingRecipe kTimeOffset{"bearing_time_offset", 0.15, 1};
inline const BearingRecipe kClean{"bearing_clean", 0.0, 2};

}  // namespace calib::testing

#endif  // CALIB_TESTS_SOLVERS_BEARING_BEARING_DIAGNOSIS_RECIPES_H_
