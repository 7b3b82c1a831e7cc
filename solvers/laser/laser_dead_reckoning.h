#ifndef CALIB_SOLVERS_LASER_LASER_DEAD_RECKONING_H_
#define CALIB_SOLVERS_LASER_LASER_DEAD_RECKONING_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/laser/laser_params.h>
#include <calib/core/se2.h>

#include <Eigen/Core>
#include <vector>

// What a person checks a laser–odometry calibration with: the sensor's path as the scan matcher
// saw it against the path the wheels give, the scan-matching residuals, and the motion the log
// covered. Paths are in the frame of the sensor's pose at the start of the log (the identity),
// one pose per interval boundary (n + 1 for n intervals).
namespace calib {

// The scan-matched displacements chained: p_{k+1} = p_k ∘ ŝ_k.
std::vector<Pose2d> ScanMatchedSensorPath(const std::vector<LaserInterval>& intervals);

// The wheels' robot displacements o_k under `odometry`, carried to the sensor with the mounting ℓ
// (ℓ⁻¹ ∘ o_k ∘ ℓ) and chained: the sensor's path as dead reckoning predicts it.
std::vector<Pose2d> DeadReckonedSensorPath(const std::vector<LaserInterval>& intervals,
                                           const OdometryParams& odometry,
                                           const Pose2d& base_T_sensor);

// The three paths a person compares: the scan-matched one and dead reckoning with the "before"
// parameters and with the calibrated ones. An interval with used[k] false (an outlier: a bad scan
// match or a slip) is chained with the same displacement in all three, the calibrated prediction,
// so that it shows as drift in none.
struct LaserPathComparison {
  std::vector<Pose2d> scan_matched, before, calibrated;
};
LaserPathComparison CompareLaserPaths(const std::vector<LaserInterval>& intervals,
                                      const LaserCalibration& before,
                                      const LaserCalibration& calibrated,
                                      const std::vector<bool>& used);

// The scan-matching error e_k = ŝ_k − ŝ_pred,k (x, y in m, θ in rad; SensorMotionError) of every
// interval under `calibration`.
std::vector<Eigen::Vector3d> LaserIntervalErrors(const std::vector<LaserInterval>& intervals,
                                                 const LaserCalibration& calibration);

// The robot's mean forward speed v (m/s) and turn rate ω (rad/s) over each interval:
// v = (r_l·φ_l + r_r·φ_r)/2, ω = (r_r·φ_r − r_l·φ_l)/b.
std::vector<Eigen::Vector2d> IntervalRobotSpeeds(const std::vector<LaserInterval>& intervals,
                                                 const OdometryParams& odometry);

// Whether each interval is within the inlier cut: ‖diag(1/σ)·e_k‖² ≤ chi2 (the calibration's
// classification when its is_inlier flags are not at hand).
std::vector<bool> ClassifyLaserInliers(const std::vector<Eigen::Vector3d>& errors,
                                       const Eigen::Vector3d& noise_sigma, double chi2 = 16.27);

}  // namespace calib

#endif  // CALIB_SOLVERS_LASER_LASER_DEAD_RECKONING_H_
