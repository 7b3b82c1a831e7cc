#ifndef CALIB_SOLVERS_BEARING_BEARING_DIAGNOSIS_H_
#define CALIB_SOLVERS_BEARING_BEARING_DIAGNOSIS_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/bearing/bearing_model.h>
#include <calib/core/status.h>
#include <calib/solvers/bearing/bearing_bundle_adjustment.h>
#include <calib/solvers/bearing/calibrate_bearing.h>
#include <calib/solvers/diagnosis/finding.h>
#include <calib/solvers/stats/change_point.h>

#include <functional>
#include <string>
#include <vector>

// `calib diagnose` for the bearing problem (Martinelli): is the bearings' clock offset from the
// encoders' (the contract's `time_offset`), hidden in biased calibration parameters?
//
//   StatusOr<BearingDiagnosis> d = DiagnoseBearing(*log);
//   for (const BearingFinding& f : d->findings) if (f.significant) use(f.statement);
//
// 1. Robust base fit (CalibrateBearing with its timing model off: stamps as sample times):
//    calibration, poses and noise levels.
// 2. Score test of τ = 0 on that fit (problems/bearing_time_offset_residual.h): the score
//    U = Σρ'·r·∂r/∂τ, the efficient information I_eff = 1/C_ττ from ceres::Covariance of the
//    problem with τ added (the calibration AND every pose projected out), the robust loss's
//    sandwich constants; statistic U²·C_ττ/(s·λ) ~ χ²₁ (s the likelihood-ratio scale, λ the
//    ratio of Newton to Gauss–Newton curvature; BearingProblem::BearingLossConstants). Concealment
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
  double change_trim = 0.05;  // Changes of the mean residual searched in [trim, 1 − trim].
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

// The bearing problem's one candidate, time_offset, as a shared Finding (vectors over
// BearingParamTable(); one_step and one_step_stddev of size 1, in s).
struct BearingFinding : Finding {
  BearingFinding() {
    name = "time_offset";
    unit = "s";
    dof = 1;
    one_step = one_step_stddev = Eigen::VectorXd::Zero(1);
    absorbed = base_shift = base_shift_sigmas = BearingParamVector::Zero();
  }
};

struct BearingDiagnosis {
  // The base calibration as `calib calibrate` reports it with its timing model off.
  BearingCalibrationResult base;
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

// Names, units and angle flags of the bearing parameters (phi, psi, eta, delta, xi), in the order
// of BearingParamVector, then of the metric set's rho, delta_r, delta_l, delta_b.
const ParamTable& BearingParamTable();

// The diagnosis in the problem-independent form of the reports (tools/report/diagnosis_json.h).
DiagnosisReport ToDiagnosisReport(const BearingDiagnosis& diagnosis);

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_BEARING_DIAGNOSIS_H_
