#include <calib/solvers/scan_matching/line_noise_bias.h>

namespace calib {

Eigen::Vector3d LineNoiseGradientBias(const Eigen::Vector2d& qa, const Eigen::Vector2d& qb,
                                      const Eigen::Vector2d& ua, const Eigen::Vector2d& ub,
                                      double alpha, const Eigen::Vector2d& rotated_point,
                                      const Eigen::Vector2d& rotated_direction, double sigma_m) {
  const double length = (qb - qa).norm();
  const Eigen::Vector2d tau = (qb - qa) / length;
  const Eigen::Vector2d n(-tau.y(), tau.x());
  const Eigen::Vector2d perp(-rotated_point.y(), rotated_point.x());
  const Eigen::Vector3d j(n.x(), n.y(), n.dot(perp));
  const Eigen::Vector3d t(tau.x(), tau.y(), tau.dot(perp));
  const auto term = [&](const Eigen::Vector2d& u, double weight) -> Eigen::Vector3d {
    return weight * n.dot(u) * (n.dot(u) * t + tau.dot(u) * j) / length;
  };
  Eigen::Vector3d bias = term(ub, alpha) + term(ua, -(1.0 - alpha));
  bias(2) += n.dot(rotated_direction) * tau.dot(rotated_direction);
  return sigma_m * sigma_m * bias;
}

}  // namespace calib
