#ifndef CALIB_SOLVERS_BEARING_BEARING_CIRCLE_FIT_H_
#define CALIB_SOLVERS_BEARING_BEARING_CIRCLE_FIT_H_

#include <calib/core/bearing/bearing_model.h>
#include <calib/core/status.h>

#include <Eigen/Core>
#include <cmath>
#include <vector>

// The bearing of a landmark seen from a circle at fixed q against the right wheel's travel s,
// β(s) = θC + arg(1 + r·e^{iχ}), χ = −ξq(s − s_n) (core/bearing/bearing_model.h, BearingCircle),
// fitted to samples: the first step of Martinelli's closed form (solvers/bearing/
// martinelli_closed_form.h), with every sample used wherever it lies in s.
namespace calib {

// The circle (ξq, node, θC, r) that best explains bearings against s, with |ξq| searched in
// [xi_min, xi_max] (both signs); the node comes back in [s_min, s_min + π/|ξq|).
StatusOr<BearingCircle> FitBearingCircle(const std::vector<double>& s_m,
                                         const std::vector<double>& bearing_rad,
                                         double xi_min_per_m, double xi_max_per_m,
                                         int max_scan_samples = 400);

// RMS of wrap(β − β̂) over the samples.
double CircleRmsResidual(const BearingCircle& c, const std::vector<double>& s,
                         const std::vector<double>& beta);

// Covariance of (ξq, s_n, θC, r) from the bearing residuals: σ̂²(JᵀJ)⁻¹ with J the derivatives of
// β = θC + atan2(r sin χ, 1 + r cos χ).
Eigen::Matrix4d CircleCovariance(const BearingCircle& c, const std::vector<double>& s,
                                 const std::vector<double>& beta);

// Minimises f on [lo, hi] by golden-section search.
template <typename F>
double GoldenMinimum(F f, double lo, double hi, int iterations = 80) {
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
  double f1 = f(x1), f2 = f(x2);
  for (int i = 0; i < iterations && hi - lo > 1e-15 * (1.0 + std::abs(lo)); ++i) {
    if (f1 < f2) {
      hi = x2, x2 = x1, f2 = f1;
      x1 = hi - g * (hi - lo), f1 = f(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2;
      x2 = lo + g * (hi - lo), f2 = f(x2);
    }
  }
  return f1 < f2 ? x1 : x2;
}

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_BEARING_CIRCLE_FIT_H_
