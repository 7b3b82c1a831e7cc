#include "benchmarks/bench_crlb.h"

#include <calib/problems/laser/laser_residual.h>

#include <Eigen/Dense>
#include <cmath>
#include <memory>

namespace calib::bench {

StatusOr<LaserCramerRao> LaserCramerRaoBound(const std::vector<LaserInterval>& intervals,
                                             const std::vector<bool>& skip,
                                             const LaserCalibration& truth,
                                             const LaserNoiseModel& noise_model) {
  const Eigen::Vector3d& scan_sigma = noise_model.scan_sigma;
  const double wheel_sigma = noise_model.wheel_sigma;
  const LaserParamVector p = truth.ToVector();
  const double* parameters[2] = {p.data(), p.data() + 3};
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> j_odometry, j_sensor;
  double* jacobians[2] = {j_odometry.data(), j_sensor.data()};
  LaserParamMatrix fisher = LaserParamMatrix::Zero();
  LaserParamMatrix bread = LaserParamMatrix::Zero(), meat = LaserParamMatrix::Zero();
  const Eigen::Matrix3d weight = scan_sigma.cwiseAbs2().cwiseInverse().asDiagonal();
  for (size_t k = 0; k < intervals.size(); ++k) {
    if (k < skip.size() && skip[k]) continue;
    // Evaluate at the noise-free measurement, so the Jacobian is that of the model, not of the
    // particular noise draw.
    LaserInterval clean = intervals[k];
    const Pose2d robot = IntervalRobotMotion(p(0), p(1), p(2), clean);
    clean.sensor_motion = SensorMotionFromRobotMotion(truth.base_T_sensor, robot);
    const std::unique_ptr<ceres::CostFunction> cost(LaserResidual::Create(clean, &identity));
    Eigen::Vector3d r;
    if (!cost->Evaluate(parameters, r.data(), jacobians)) {
      return Status::Internal("a residual could not be evaluated at the truth");
    }
    Eigen::Matrix<double, 3, 6> j;
    j << j_odometry, j_sensor;
    // The error is ŝ − ŝ_pred in the scan matcher's own frame, so the noise on sm enters as is.
    Eigen::Matrix3d noise = scan_sigma.cwiseAbs2().asDiagonal();
    if (wheel_sigma > 0.0 && clean.steps.empty()) {
      // ∂e/∂(φ_l, φ_r) by central differences; the error is smooth in the speeds.
      Eigen::Matrix<double, 3, 2> j_speed;
      const double h = 1e-6;
      for (int w = 0; w < 2; ++w) {
        LaserInterval plus = clean, minus = clean;
        (w == 0 ? plus.left_speed : plus.right_speed) += h;
        (w == 0 ? minus.left_speed : minus.right_speed) -= h;
        j_speed.col(w) = (LaserResidual::Error(plus, parameters[0], parameters[1]) -
                          LaserResidual::Error(minus, parameters[0], parameters[1])) /
                         (2 * h);
      }
      noise += wheel_sigma * wheel_sigma * j_speed * j_speed.transpose();
    }
    fisher += j.transpose() * noise.inverse() * j;
    bread += j.transpose() * weight * j;
    meat += j.transpose() * weight * noise * weight * j;
  }
  const Eigen::LDLT<LaserParamMatrix> ldlt(fisher);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0.0).all()) {
    return Status::NotObservable("the Fisher information is singular");
  }
  const LaserParamMatrix bread_inverse = bread.inverse();
  return LaserCramerRao{ldlt.solve(LaserParamMatrix::Identity()),
                        bread_inverse * meat * bread_inverse};
}

}  // namespace calib::bench
