#ifndef CALIB_SOLVERS_LASER_LASER_JITTER_REFIT_H_
#define CALIB_SOLVERS_LASER_LASER_JITTER_REFIT_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/status.h>
#include <calib/solvers/laser/calibrate_laser.h>

#include <Eigen/Core>
#include <vector>

// The interval-jitter step of CalibrateLaser (internal): σ_j per log at the base fit and, when one
// is significant, the refit with per-interval whitening Σ_k^{-1/2}.
namespace calib {

// Fills result->interval_jitter with σ_j per log at the base fit; true when one is significant
// (the refit is then due, and the base fit's covariance is not needed). `errors`, when given,
// holds every log's errors at the base fit (saves a pass).
bool EstimateBaseFitJitter(const std::vector<const std::vector<LaserInterval>*>& logs,
                           const LaserCalibrationOptions& options, LaserCalibrationResult* result,
                           const std::vector<std::vector<Eigen::Vector3d>>* errors = nullptr);

// After EstimateBaseFitJitter said true: replaces the estimate, inliers, noise levels, covariance
// (and its seconds) and observability by the refit's, sets jitter_refit and adds the statement
// that only this weaker treatment was possible.
Status RefitWithIntervalJitter(const std::vector<const std::vector<LaserInterval>*>& logs,
                               const LaserCalibrationOptions& options,
                               LaserCalibrationResult* result);

}  // namespace calib

#endif  // CALIB_SOLVERS_LASER_LASER_JITTER_REFIT_H_
