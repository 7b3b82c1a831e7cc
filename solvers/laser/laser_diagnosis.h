#ifndef CALIB_SOLVERS_LASER_LASER_DIAGNOSIS_H_
#define CALIB_SOLVERS_LASER_LASER_DIAGNOSIS_H_

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include <calib/core/laser/laser_params.h>
#include <calib/core/laser/laser_log.h>
#include <calib/core/status.h>
#include <calib/problems/laser/laser_effect_residual.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/stats/change_point.h>
#include <calib/solvers/laser/laser_effect_fit.h>

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
};

struct LaserFinding {
  LaserEffect effect = LaserEffect::kTimeOffset;
  std::string name;
  std::string unit;             // Of value.
  bool significant = false;     // Adopted: score test (Holm), likelihood ratio and held-out agree.
  bool confounded = false;      // The data cannot separate it from the base parameters.
  bool no_information = false;  // The log's motion does not excite it at all.
  std::vector<std::string> confounded_with;
  int step = 0;  // Forward step of the last score test (1-based).
  // Score test (at the step it was last tested, given the effects adopted before).
  double statistic = 0.0;
  int dof = 0;
  double p_value = 1.0;
  double holm_level = 0.0;  // The level its p-value was compared with (0: not reached).
  bool score_significant = false;
  double concealment = 0.0;  // Share absorbable by the parameters already fitted.
  Eigen::VectorXd one_step;  // One-step γ̂ and its standard deviation.
  Eigen::VectorXd one_step_stddev;
  LaserParamVector absorbed = LaserParamVector::Zero();  // B·γ̂: what the fit without it took on.
  // Confirmation (when it was refitted).
  bool refitted = false;
  double lr_statistic = 0.0;
  double lr_p_value = 1.0;
  double delta_aic = 0.0;  // AIC(without) − AIC(with): positive favours the effect.
  double delta_bic = 0.0;
  double heldout_cost_before = 0.0;  // Σ over held-out blocks of ½Σρ.
  double heldout_cost_after = 0.0;
  double heldout_rms_before = 0.0;  // Whitened RMS of held-out inliers.
  double heldout_rms_after = 0.0;
  double heldout_reduction = 0.0;  // 1 − cost_after/cost_before.
  // The value in the contract's meaning (γ; the change time for wheel_radius_change) and its
  // standard deviation: from the final fit when adopted, else the one-step estimate.
  double value = 0.0;
  double stddev = 0.0;
  double r_l_after = 0.0, r_r_after = 0.0;  // wheel_radius_change.
  double r_l_after_stddev = 0.0, r_r_after_stddev = 0.0;
  // Adopted: the refit's change of the base parameters, θ(without) − θ(with), in m/rad and in
  // units of the baseline's standard deviations.
  LaserParamVector base_shift = LaserParamVector::Zero();
  // Adopted: the share of the fitted effect's signal (‖·‖² of its residual change at the final
  // parameters) that the base fit had hidden by shifting its parameters.
  double absorbed_share = 0.0;
  LaserParamVector base_shift_sigmas = LaserParamVector::Zero();
  MismatchLocation location;
  CovariateProfile profile;  // Adopted: residuals against location.covariate.
  std::string statement;
};

struct LaserDiagnosis {
  LaserFitReport baseline;
  LaserFitReport final_fit;
  std::vector<LaserFinding> findings;  // One per candidate, adopted ones first (in order).
  std::vector<LaserEffect> adopted;
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

}  // namespace calib

#endif  // CALIB_SOLVERS_LASER_LASER_DIAGNOSIS_H_
