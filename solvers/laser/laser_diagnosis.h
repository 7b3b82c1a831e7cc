#ifndef CALIB_SOLVERS_LASER_LASER_DIAGNOSIS_H_
#define CALIB_SOLVERS_LASER_LASER_DIAGNOSIS_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/laser/laser_params.h>
#include <calib/core/status.h>
#include <calib/problems/laser/laser_effect_residual.h>
#include <calib/solvers/diagnosis/finding.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/laser/laser_effect_fit.h>
#include <calib/solvers/stats/change_point.h>

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

// `calib diagnose` for the laser problem: finds physics that the base model leaves out, even
// when the base parameters absorb it and the residuals look like noise.
//
//   StatusOr<LaserDiagnosis> d = DiagnoseLaser(log->intervals);
//   for (const LaserFinding& f : d->findings) if (f.significant) use(f.statement);
//
// 1. Robust base fit (CalibrateLaser), whitened by its robust noise level.
// 2. For every candidate effect (problems/laser_effect_residual.h) a score test at γ = 0 with
//    the base parameters profiled out, its concealment ratio, the one-step estimate of γ and of
//    the shift the base fit took on. The radius change is scanned over the interval boundaries
//    (sup-score test). Effects the data cannot separate from the base parameters are flagged as
//    confounded and never tested.
// 3. Holm's step-down control over the remaining candidates; the strongest significant one is
//    refitted with Ceres and adopted only if a likelihood-ratio test at the same level AND
//    held-out blocks (K-fold block cross-validation) confirm it; then the others are re-tested
//    given it (forward stepwise).
// 4. Location: the covariate the effect's signal follows and the time windows where its score
//    accumulates (CUSUM segmentation); residual structure before and after, so that a mismatch
//    outside the library is still described.
namespace calib {

// The candidates' effects in the contract's words; the names of kLaserEffectInfo.
std::string LaserEffectName(LaserEffect effect);
StatusOr<LaserEffect> ParseLaserEffect(const std::string& name);
std::vector<LaserEffect> AllLaserEffects();

enum class BoundaryChoice {
  kAuto,               // Fit both boundary-speed models when an effect uses them; keep the better.
  kPiecewiseConstant,  // Speeds constant within intervals (step changes at the boundaries).
  kSmooth,             // Speeds vary smoothly.
};

// Sizes a wheel does not have: a refit beyond them is reported as a structure in the residuals
// that follows the effect's covariate, not adopted as that physics (data/diagnose/README.md).
struct LaserPlausibility {
  double speed_radius_per_rad_s = 0.1;  // |γ| of the speed-dependent radius (1 % per 0.1 rad/s).
  double radius_step = 0.015;           // |γ_l|, |γ_r| of a radius change (1.5 %).
  // The lateral slip's slip angle γ·ω at the log's 95th-percentile turn rate (rad).
  double lateral_slip_angle_rad = 0.1;
  double longitudinal_slip_s = 0.5;  // |γ| of the longitudinal slip.
};

struct LaserDiagnosisOptions {
  LaserCalibrationOptions calibration;  // The base fit.
  std::vector<LaserEffect> candidates = AllLaserEffects();
  double alpha = 0.01;        // Family-wise error rate of each step (Holm).
  int max_effects = 3;        // At most this many effects adopted.
  int cv_blocks = 5;          // Contiguous held-out blocks.
  int hac_lag = 2;            // Bartlett lags of the score variance (neighbouring scans correlate).
  double change_trim = 0.05;  // Radius changes searched in [trim, 1 − trim] of the log.
  BoundaryChoice boundary = BoundaryChoice::kAuto;
  int covariate_bins = 10;
  int change_profile_steps = 4;  // Sub-steps per interval when locating a change time.
  // Timing candidates (stamp_jitter) are tested, confirmed and modelled before any physical
  // candidate, so that the physical ones are tested with the timing model in the base.
  bool timing_candidates = true;
  // The intervals lie between estimated sample times (the latent-time calibration of raw
  // streams), not between stamps.
  bool sample_times_estimated = false;
  LaserPlausibility plausibility;
  // Only what the model screen reads (laser_model_screen.h): the findings' score tests and the
  // base fit's residual structure. No fit reports (their covariances), covariate profiles,
  // values or statements.
  bool screen_only = false;
  std::function<void(const std::string&)> progress;
};

// A fit of the calibration with a set of effects.
struct LaserFitReport {
  std::vector<LaserEffect> effects;
  LaserCalibration estimate;
  LaserParamVector stddev = LaserParamVector::Zero();
  LaserEffectVector gamma = LaserEffectVector::Zero();
  LaserEffectVector gamma_stddev = LaserEffectVector::Zero();
  BoundarySpeedModel boundary = BoundarySpeedModel::kSmooth;
  double change_time_s = -1.0;  // From the log start; < 0 without a radius change.
  double change_time_stddev_s = 0.0;
  Eigen::Vector3d rms = Eigen::Vector3d::Zero();  // Unwhitened inlier error RMS (m, m, rad).
  double robust_cost = 0.0;                       // ½Σρ, whitened.
  int inliers = 0;
  // σ of the boundary-stamp jitter modelled in this fit (each interval whitened by its own
  // covariance); 0 when not modelled.
  double stamp_jitter_s = 0.0;
  double stamp_jitter_stddev_s = 0.0;
};

// A finding of the laser problem: the shared Finding (vectors over kLaserParams) with its effect
// and, for wheel_radius_change, the radii after the change.
struct LaserFinding : Finding {
  LaserEffect effect = LaserEffect::kTimeOffset;
  double r_l_after = 0.0, r_r_after = 0.0;  // wheel_radius_change.
  double r_l_after_stddev = 0.0, r_r_after_stddev = 0.0;
};

struct LaserDiagnosis {
  LaserFitReport baseline;
  LaserFitReport final_fit;
  std::vector<LaserFinding> findings;  // One per candidate, adopted ones first (in order).
  std::vector<LaserEffect> adopted;
  // The timing candidates (stamp_jitter), tested before the physical ones; those adopted are
  // named in adopted_timing (they come first in the report's `adopted`).
  std::vector<Finding> timing_findings;
  std::vector<std::string> adopted_timing;
  std::vector<CovariateProfile> covariates;
  ResidualStructure structure_before;
  ResidualStructure structure_after;
  int samples = 0;
  int steps = 0;
  double seconds = 0.0;
  std::vector<std::string> notes;  // Plain-words remarks (e.g. why an effect was not adopted).
};

// Covariates the location reports, in order: time (s), speed v (m/s), angular_rate ω (rad/s),
// v_times_omega (m/s²), acceleration dv/dt (m/s²), angular_acceleration dω/dt (rad/s²).
const std::vector<std::string>& LaserCovariateNames();

StatusOr<LaserDiagnosis> DiagnoseLaser(const std::vector<LaserInterval>& intervals,
                                       const LaserDiagnosisOptions& options = {});

// The diagnosis in the problem-independent form of the reports (tools/report/diagnosis_json.h).
DiagnosisReport ToDiagnosisReport(const LaserDiagnosis& diagnosis);

}  // namespace calib

#endif  // CALIB_SOLVERS_LASER_LASER_DIAGNOSIS_H_
