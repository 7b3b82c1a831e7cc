#ifndef CALIB_SOLVERS_DIAGNOSIS_FINDING_H_
#define CALIB_SOLVERS_DIAGNOSIS_FINDING_H_

#include <calib/core/param_info.h>
#include <calib/solvers/stats/change_point.h>

#include <Eigen/Core>
#include <limits>
#include <string>
#include <utility>
#include <vector>

// What `calib diagnose` says about one candidate effect and about one fit, for any problem.
// Vectors over the base parameters (absorbed, base_shift, ...) are in the order of the
// problem's parameter table (a ParamInfo per entry: kLaserParams, BearingParamTable()).
namespace calib {

// The parameters' table of a problem, in the order of its parameter vectors.
using ParamTable = std::vector<ParamInfo>;

// The held-out blocks' score of one model: Σ over the left-out samples of ½ρ, and the inlier
// errors' sum of squares (per sample `components` of them).
struct HeldOutScore {
  double cost = 0.0;
  double sum_sq = 0.0;
  int count = 0;
  int components = 1;
  double rms() const;
};

// The likelihood-ratio test of a refit: 2·Δ(½Σρ)/κ, its p-value and information criteria.
struct LikelihoodRatio {
  double statistic = 0.0;
  double p_value = 1.0;
  double delta_aic = 0.0;  // AIC(without) − AIC(with): positive favours the effect.
  double delta_bic = 0.0;
};

struct Finding {
  std::string name;             // The contract's effect name.
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
  Eigen::VectorXd one_step;  // One-step estimate of the effect and its standard deviation.
  Eigen::VectorXd one_step_stddev;
  Eigen::VectorXd absorbed;  // B·γ̂: what the fit without it took on (per base parameter).
  // Confirmation (when it was refitted).
  bool refitted = false;
  double lr_statistic = 0.0;
  double lr_p_value = 1.0;
  double delta_aic = 0.0;
  double delta_bic = 0.0;
  double heldout_cost_before = 0.0;  // Σ over held-out blocks of ½Σρ.
  double heldout_cost_after = 0.0;
  double heldout_rms_before = 0.0;  // RMS of held-out inliers.
  double heldout_rms_after = 0.0;
  double heldout_reduction = 0.0;  // 1 − cost_after/cost_before.
  // The value in the contract's meaning and its standard deviation: from the final fit when
  // adopted, else the one-step estimate.
  double value = 0.0;
  double stddev = 0.0;
  // Adopted: the refit's change of the base parameters, θ(without) − θ(with), and the same in
  // units of the baseline's standard deviations (0 where that is 0).
  Eigen::VectorXd base_shift;
  Eigen::VectorXd base_shift_sigmas;
  // Adopted: the share of the effect's signal the base fit had hidden by shifting its
  // parameters (NaN where the problem does not compute it).
  double absorbed_share = std::numeric_limits<double>::quiet_NaN();
  // Confirmed, but of a size the physics does not have: reported as a structure in the
  // residuals that follows `follows` (a covariate), not adopted. `reason` says why.
  bool implausible = false;
  std::string implausible_reason;
  std::string follows;
  MismatchLocation location;
  CovariateProfile profile;  // Adopted: residuals against location.covariate.
  std::string statement;

  bool testable() const { return !confounded && !no_information; }
};

// One effect's value in a fit (γ; for a change, its time and the γ of each side).
struct EffectValue {
  std::string name;
  double value = 0.0;
  double stddev = 0.0;
  std::string unit;
  Eigen::VectorXd gamma;  // When the value is not γ itself (e.g. a change time).
  Eigen::VectorXd gamma_stddev;
};

// A fit of the calibration with a set of effects, over a named parameter vector.
struct FitReport {
  std::vector<std::string> effects;
  ParamTable params;
  Eigen::VectorXd estimate;
  Eigen::VectorXd stddev;
  Eigen::VectorXd rms;  // Unwhitened inlier error RMS per residual component.
  std::vector<std::string> rms_units;
  double robust_cost = 0.0;  // ½Σρ, whitened.
  int inliers = 0;
  std::vector<EffectValue> effect_values;
  std::vector<std::pair<std::string, std::string>> words;  // Problem-specific (key, text).
};

// A finding with the problem's further named results (e.g. r_l_after for a radius change).
struct ReportedFinding {
  Finding finding;
  std::vector<std::pair<std::string, double>> extra;
};

// The whole diagnosis in the problem-independent form the reports write.
struct DiagnosisReport {
  std::string problem;  // "laser", "bearing".
  std::string units;
  int samples = 0;
  int steps = 0;
  double seconds = 0.0;
  ParamTable params;
  FitReport baseline;
  FitReport final_fit;
  std::vector<ReportedFinding> findings;
  std::vector<std::string> adopted;
  std::vector<CovariateProfile> covariates;
  ResidualStructure structure_before;
  ResidualStructure structure_after;
  std::vector<std::string> notes;
};

// The fields every problem's diagnosis result has in common (D: LaserDiagnosis,
// BearingDiagnosis), copied into `out`.
template <typename D>
void CopyCommonFields(const D& diagnosis, DiagnosisReport* out) {
  out->samples = diagnosis.samples;
  out->seconds = diagnosis.seconds;
  out->covariates = diagnosis.covariates;
  out->structure_before = diagnosis.structure_before;
  out->structure_after = diagnosis.structure_after;
  out->notes = diagnosis.notes;
}

}  // namespace calib

#endif  // CALIB_SOLVERS_DIAGNOSIS_FINDING_H_
