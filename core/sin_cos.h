#ifndef CALIB_CORE_SIN_COS_H_
#define CALIB_CORE_SIN_COS_H_

#include <cmath>

namespace calib {

// sin θ and cos θ together. The per-interval passes take them of a robot's turn in one interval,
// nearly always within ±π/4, where the Taylor series to θ¹⁷ and θ¹⁸ are within 1e-19 of them
// and Horner's rule in θ² rounds to within an ulp: a few multiply-adds instead of libm's sincos
// (a tenth of a real set's run). Beyond ±π/4 (and for NaN) libm's.
inline void SinCos(double angle, double* sin_angle, double* cos_angle) {
  constexpr double kQuarterPi = 0.78539816339744830962;
  if (!(std::abs(angle) <= kQuarterPi)) {
    *sin_angle = std::sin(angle);
    *cos_angle = std::cos(angle);
    return;
  }
  const double z = angle * angle;
  // (−1)ᵏ/(2k+1)!, k ≥ 1, and (−1)ᵏ/(2k)!, k ≥ 2.
  const double s =
      -1.0 / 6 +
      z * (1.0 / 120 +
           z * (-1.0 / 5040 + z * (1.0 / 362880 + z * (-1.0 / 39916800 +
                                                       z * (1.0 / 6227020800 +
                                                            z * (-1.0 / 1307674368000 +
                                                                 z * (1.0 / 355687428096000)))))));
  const double c =
      1.0 / 24 +
      z * (-1.0 / 720 +
           z * (1.0 / 40320 +
                z * (-1.0 / 3628800 +
                     z * (1.0 / 479001600 +
                          z * (-1.0 / 87178291200 +
                               z * (1.0 / 20922789888000 + z * (-1.0 / 6402373705728000)))))));
  *sin_angle = angle + angle * z * s;
  // 1 − z/2 with its rounding error carried into the small terms (as fdlibm's __kernel_cos).
  const double half_z = 0.5 * z, w = 1.0 - half_z;
  *cos_angle = w + (((1.0 - w) - half_z) + z * z * c);
}

}  // namespace calib

#endif  // CALIB_CORE_SIN_COS_H_
