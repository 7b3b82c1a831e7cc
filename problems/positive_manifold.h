#ifndef CALIB_PROBLEMS_POSITIVE_MANIFOLD_H_
#define CALIB_PROBLEMS_POSITIVE_MANIFOLD_H_

#include <ceres/manifold.h>

#include <cmath>

namespace calib {

// Keeps every coordinate of a block strictly positive (wheel radii, wheelbase) by moving in
// relative steps: x ⊞ δ = x ⊙ exp(δ), y ⊟ x = log(y / x). Unlike Ceres' bounds, which add a
// projected line search with an extra Jacobian evaluation to every step, this costs nothing.
template <int kSize>
class PositiveManifold : public ceres::Manifold {
 public:
  int AmbientSize() const override { return kSize; }
  int TangentSize() const override { return kSize; }

  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    for (int i = 0; i < kSize; ++i) x_plus_delta[i] = x[i] * std::exp(delta[i]);
    return true;
  }
  bool PlusJacobian(const double* x, double* jacobian) const override {
    for (int i = 0; i < kSize * kSize; ++i) jacobian[i] = 0.0;
    for (int i = 0; i < kSize; ++i) jacobian[i * kSize + i] = x[i];
    return true;
  }
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    for (int i = 0; i < kSize; ++i) y_minus_x[i] = std::log(y[i] / x[i]);
    return true;
  }
  bool MinusJacobian(const double* x, double* jacobian) const override {
    for (int i = 0; i < kSize * kSize; ++i) jacobian[i] = 0.0;
    for (int i = 0; i < kSize; ++i) jacobian[i * kSize + i] = 1.0 / x[i];
    return true;
  }
};

}  // namespace calib

#endif  // CALIB_PROBLEMS_POSITIVE_MANIFOLD_H_
