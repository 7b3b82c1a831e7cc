#ifndef CALIB_SOLVERS_BEARING_BEARING_DIAGNOSIS_H_
#define CALIB_SOLVERS_BEARING_BEARING_DIAGNOSIS_H_

#include <functional>
#include <string>
#include <vector>

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/bearing/bearing_model.h>
#include <calib/core/status.h>
#include <calib/solvers/bearing/bearing_bundle_adjustment.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <calib/solvers/stats/change_point.h>

// `calib diagnose` for the bearing problem (Martinelli): is the bearings' clock offset from the
// encoders' (the contract's `time_offset`), hidden in biased calibration parameters?
//
//   StatusOr<BearingDiagnosis> d = DiagnoseBearing(*log);
//   for (const BearingFinding& f : d->findings) if (f.significant) use(f.statement);
//
// 1. Robust base fit (CalibrateBearing): calibration, poses and noise levels.
// 2. Score test of τ = 0 on that fit (problems/bearing_time_offset_residual.h): the score
//    U = Σρ'·r·∂r/∂τ, the efficient information I_eff = 1/C_ττ from ceres::Covariance of the
//    problem with τ added (the calibration AND every pose projected out), the robust loss's
//    sandwich constants; statistic U²·C_ττ/(s·λ) ~ χ²₁ (s the likelihood-ratio scale, λ the
//    ratio of Newton to Gauss–Newton curvature; BearingProblem::LossConstants). Concealment
//    1 − I_eff/A_ττ with A_ττ = Σρ'·(∂r/∂τ)²; one-step τ̂ = −C_ττ·U/λ and the shift the base fit
//    took on, θ(without) − θ(with) ≈ C_θτ·U/λ.
// 3. Confirmation: the refit with τ free (noise levels held at the base fit's), a likelihood-
//    ratio test at the same level, and held-out blocks (every run cut into K contiguous blocks;
//    fold f leaves block f of every run out of both fits and scores its bearings).
// 4. Location: CUSUM segments of the score density over time and the covariate the residuals
//    follow (time, speed, angular rate, predicted bearing rate); structure left in the residuals
//    before and after, reported even when τ does not explain it.
// On constant-speed circles a time offset only moves each run's start along its circle (the
// poses absorb it exactly, no bias): such logs carry information on τ only at speed changes.
namespace calib {

struct BearingDiagnosisOptions {
  BearingCalibrationOptions calibration;  // The base fit.
  double alpha = 0.01;                    // Family-wise error rate (one candidate: its level).
  int cv_blocks = 5;                      // Contiguous held-out blocks per run.
  int covariate_bins = 10;
  std::function<void(const std::string&)> progress;
};

// A fit of the calibration with or without τ.
struct BearingFitReport {
  bool with_time_offset = false;
  BearingParams estimate;
  BearingParamVector stddev = BearingParamVector::Zero();
  bool has_metric = false;  // With an initial distance: the metric set.
  BearingMetricParams metric;
  BearingMetricVector metric_stddev = BearingMetricVector::Zero();
  double time_offset_s = 0.0;
  double time_offset_stddev_s = 0.0;
  double rms_rad = 0.0;      // Of the inlier bearings' errors.
  double robust_cost = 0.0;  // ½Σρ (whitened, bearings and odometry).
  int inliers = 0;
};

struct BearingFinding {
  std::string name = "time_offset";
  std::string unit = "s";
  bool significant = false;     // Adopted: score test, likelihood ratio and held-out agree.
  bool confounded = false;      // The poses and calibration absorb it entirely.
  bool no_information = false;  // The log's motion does not excite it.
  std::vector<std::string> confounded_with;
  double statistic = 0.0;
  int dof = 1;
  double p_value = 1.0;
  double holm_level = 0.0;
  bool score_significant = false;
  double concealment = 0.0;  // Share of its information the base unknowns absorb.
  double one_step = 0.0, one_step_stddev = 0.0;
  BearingParamVector absorbed = BearingParamVector::Zero();  // One-step θ(without) − θ(with).
  bool refitted = false;
  double lr_statistic = 0.0;
  double lr_p_value = 1.0;
  double delta_aic = 0.0, delta_bic = 0.0;
  double heldout_cost_before = 0.0, heldout_cost_after = 0.0;
  double heldout_rms_before = 0.0, heldout_rms_after = 0.0;  // Held-out inlier errors (rad).
  double heldout_reduction = 0.0;
  double value = 0.0;  // τ (s): the final fit's when adopted, else the one-step estimate.
  double stddev = 0.0;
  // Adopted: the refit's change θ(without) − θ(with) and in the baseline's sigmas.
  BearingParamVector base_shift = BearingParamVector::Zero();
  BearingParamVector base_shift_sigmas = BearingParamVector::Zero();
  MismatchLocation location;
  CovariateProfile profile;  // Residuals against location.covariate, before and after.
  std::string statement;
};

struct BearingDiagnosis {
  BearingCalibrationResult base;  // The base calibration as `calib calibrate` reports it.
  BearingFitReport baseline;
  BearingFitReport final_fit;
  std::vector<BearingFinding> findings;
  std::vector<std::string> adopted;
  std::vector<CovariateProfile> covariates;
  ResidualStructure structure_before;
  ResidualStructure structure_after;
  int samples = 0;
  double seconds = 0.0;
  std::vector<std::string> notes;
};

// Covariates of the location, in order: time (s from the log start), speed v (m/s, nominal),
// angular_rate ω (rad/s), bearing_rate (rad/s, the predicted rate of the bearing: the time
// offset's signature).
const std::vector<std::string>& BearingCovariateNames();

StatusOr<BearingDiagnosis> DiagnoseBearing(const BearingLog& log,
                                           const BearingDiagnosisOptions& options = {});

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_BEARING_DIAGNOSIS_H_
