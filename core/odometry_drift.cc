#include <calib/core/odometry_drift.h>

#include <algorithm>
#include <cmath>

namespace calib {

OdometryDrift DriftOf(const OdometryParams& used, const OdometryParams& actual) {
  const double left = used.left_radius_m / actual.left_radius_m;
  const double right = used.right_radius_m / actual.right_radius_m;
  OdometryDrift d;
  d.distance_mm_per_m = 1e3 * (0.5 * (left + right) - 1.0);
  d.heading_deg_per_m = (right - left) / used.wheelbase_m * 180.0 / M_PI;
  d.turn_deg_per_turn =
      360.0 * (actual.wheelbase_m / used.wheelbase_m * 0.5 * (left + right) - 1.0);
  return d;
}

OdometryDrift DriftFromUncertainty(const OdometryParams& c, const Eigen::Matrix3d& covariance) {
  const double rl = c.left_radius_m, rr = c.right_radius_m, b = c.wheelbase_m;
  const auto sigma = [&](const Eigen::Vector3d& gradient) {
    return std::sqrt(std::max(0.0, gradient.dot(covariance * gradient)));
  };
  // Gradients of the three errors in the true (r_l, r_r, b) at the estimate.
  OdometryDrift d;
  d.distance_mm_per_m = 1e3 * sigma(Eigen::Vector3d(0.5 / rl, 0.5 / rr, 0.0));
  d.heading_deg_per_m = 180.0 / M_PI * sigma(Eigen::Vector3d(1.0 / (rl * b), -1.0 / (rr * b), 0));
  d.turn_deg_per_turn = 360.0 * sigma(Eigen::Vector3d(0.5 / rl, 0.5 / rr, -1.0 / b));
  return d;
}

}  // namespace calib
