#ifndef CALIB_TESTS_PROBLEMS_LASER_LASER_EFFECT_GAMMA_H_
#define CALIB_TESTS_PROBLEMS_LASER_LASER_EFFECT_GAMMA_H_

#include <calib/problems/laser/laser_effect_residual.h>

// The effect block γ of LaserEffectResidual with one effect switched on (the tests of the
// residual, of the diagnosis' simulated logs and of the injections into the published ones).
namespace calib::testing {

using EffectVector = Eigen::Matrix<double, kNumLaserEffectParams, 1>;

inline EffectVector Gamma(LaserEffect effect, double value, double second = 0.0) {
  EffectVector gamma = EffectVector::Zero();
  gamma(EffectInfo(effect).offset) = value;
  if (EffectInfo(effect).size > 1) gamma(EffectInfo(effect).offset + 1) = second;
  return gamma;
}

}  // namespace calib::testing

#endif  // CALIB_TESTS_PROBLEMS_LASER_LASER_EFFECT_GAMMA_H_
