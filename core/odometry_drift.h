#ifndef CALIB_CORE_ODOMETRY_DRIFT_H_
#define CALIB_CORE_ODOMETRY_DRIFT_H_

#include <calib/core/diff_drive.h>

#include <Eigen/Core>

// How far dead reckoning drifts when the odometry uses one set of wheel parameters and the wheels
// are another, in the units a robot engineer checks. With ρ_l = r_l,used/r_l,true and likewise
// ρ_r, over a truly straight metre (r_l φ_l = r_r φ_r) and a true turn on the spot:
//   distance error = ½(ρ_l + ρ_r) − 1            (× 1000 mm per m),
//   heading error  = (ρ_r − ρ_l)/b_used           (rad per m),
//   turn error     = (b_true/b_used)·½(ρ_l + ρ_r) − 1   (× 360° per turn).
namespace calib {

struct OdometryDrift {
  double distance_mm_per_m = 0.0;
  double heading_deg_per_m = 0.0;
  double turn_deg_per_turn = 0.0;
};

// Signed drift of odometry run with `used` when the wheels are `actual` (+: it over-reads
// distance, sees a left turn when driving straight, over-reads a turn).
OdometryDrift DriftOf(const OdometryParams& used, const OdometryParams& actual);

// The 1σ drift that the calibration's own uncertainty leaves (the formulas above to first order
// in the error), `covariance` of (r_l, r_r, b).
OdometryDrift DriftFromUncertainty(const OdometryParams& calibrated,
                                   const Eigen::Matrix3d& covariance);

}  // namespace calib

#endif  // CALIB_CORE_ODOMETRY_DRIFT_H_
