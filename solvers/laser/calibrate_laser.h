#ifndef CALIB_SOLVERS_LASER_CALIBRATE_LASER_H_
#define CALIB_SOLVERS_LASER_CALIBRATE_LASER_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/laser/laser_params.h>
#include <calib/core/status.h>
#include <calib/solvers/laser/censi_closed_form.h>
#include <calib/solvers/laser/laser_consistency.h>
#include <calib/solvers/laser/laser_motion.h>
#include <calib/solvers/laser/laser_observability.h>
#include <calib/solvers/laser/laser_refinement.h>
#include <calib/solvers/timing/interval_jitter.h>

#include <Eigen/Core>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

// Laser–odometry calibration in one call: closed form → robust Ceres refinement with the scan
// noise estimated from the data → covariance → observability report.
//
//   calib::StatusOr<calib::LaserLog> log = calib::ReadLaserLog("robot.tuple");
//   calib::StatusOr<calib::LaserCalibrationResult> result = calib::CalibrateLaser(log->intervals);
//   if (result.ok()) use(result->estimate, result->stddev);
namespace calib {

struct LaserCalibrationResult;

// The refinement's first, convex stage (under the loss before it redescends to Tukey's): where
// it started, the noise level that whitened it, its options and its end. Another calibration of
// the same log that stops there (the model screen's base fit) takes it instead of solving again.
struct LaserConvexStage {
  LaserCalibration start;
  std::vector<Eigen::Vector3d> noise_sigma;  // Per log.
  LaserRefinementOptions refinement;
  LaserCalibration estimate;
  int iterations = 0;
  bool converged = true;
  std::string not_converged;  // Why it stopped, when it did not converge.

  // Whether a solve from `start` whitened by `noise_sigma` under `refinement`, without the
  // redescending stage, would be this stage (the same figures, bit for bit).
  bool Replaces(const LaserCalibration& start, const std::vector<Eigen::Vector3d>& noise_sigma,
                const LaserRefinementOptions& refinement) const;
};

struct LaserCalibrationOptions {
  LaserRefinementOptions refinement;
  // Fit, re-estimate the scan noise from the residuals, fit again while it changes by more than
  // 1 %: at most this many fits.
  int noise_rounds = 3;
  // Scan-matching noise σ (x, y, θ) when known; estimated from the data when empty.
  std::optional<Eigen::Vector3d> noise_sigma;
  // Intervals whose squared whitened residual exceeds this are outliers (χ²₃ at 99.9 %).
  double inlier_chi2 = 16.27;
  // Tuple/CSV logs: estimate the jitter σ_j of the interval boundary stamps after the base fit
  // (solvers/timing/interval_jitter.h) and, when it is significant, refit with each interval
  // whitened by its own covariance. Logs read from raw streams should turn this off (the
  // latent-time calibration models their timing). Not significant: the result is the base fit's.
  bool interval_jitter = true;
  IntervalJitterOptions jitter;
  // Only the estimate is wanted (the seed of another fit, as the diagnosis's base fit): stop
  // after the refinement and the inliers, without the covariance, the jitter treatment and the
  // checks (the result's other members keep their defaults).
  bool estimate_only = false;
  // The intervals' consensus screen when already computed under the default options (the input
  // checks do: LaserInputCheckOptions::consensus_screen); one log only. Null: computed here.
  std::shared_ptr<const ConsensusScreen> consensus_screen;
  // The closed forms of the same single log from another calibration (the model screen takes its
  // calibration's): the result's closed_form … seed_trimmed, and a failed trimming's warning, are
  // copied from it instead of computed, and its convex_stage replaces the first solve when it
  // applies (LaserConvexStage::Replaces). Null: computed here.
  std::shared_ptr<const LaserCalibrationResult> closed_forms;
  // When closed_forms is null: called once the checks of the log are done, for the closed forms
  // as above (it may wait for another calibration to hand them on); may return null, or be empty.
  std::function<std::shared_ptr<const LaserCalibrationResult>()> await_closed_forms;
  // Called with the result once its closed forms are in, and its convex stage when the
  // refinement has one (for another calibration that waits for them); may be empty.
  std::function<void(const LaserCalibrationResult&)> closed_forms_done;
  // Called with a line of progress for long runs; may be empty.
  std::function<void(const std::string&)> progress;
};

struct LaserCalibrationResult {
  LaserCalibration estimate;
  LaserParamMatrix covariance = LaserParamMatrix::Zero();
  LaserParamVector stddev = LaserParamVector::Zero();
  // The paper's closed form on all data but the gross intervals (censi_consensus.h).
  CensiClosedFormResult closed_form;
  int gross_intervals = 0;  // Left out of the closed forms by the consensus screen.
  std::string gross_note;   // How many and the first, in words ("" when none).
  CensiClosedFormResult closed_form_trimmed;  // With its trimming: the refinement's seed.
  bool seed_trimmed = true;  // False: the trimming failed and the seed is `closed_form`.
  // The refinement's convex stage, kept when closed_forms_done hands it on (one log, a loss that
  // redescends, no warm start).
  std::optional<LaserConvexStage> convex_stage;
  int samples = 0;
  int inliers = 0;
  std::vector<std::vector<bool>> is_inlier;  // Per log, per interval.
  std::vector<Eigen::Vector3d> noise_sigma;  // Per log: the scan noise of its inliers.
  // Per log: the robust noise level of all its intervals (RobustNoiseSigma of their errors, or
  // the given one) at `estimate`, the refinement's last; empty after a jitter refit moved it.
  std::vector<Eigen::Vector3d> robust_noise_sigma;
  LaserMotionCensus census;
  LaserObservability observability;
  // Timing-free totals over long windows, wheel model against sensor (warnings also in `warnings`).
  LaserConsistency consistency;
  double covariance_scale = 1.0;  // The loss correction κ applied to Ceres' covariance.
  std::string loss;               // The refinement's losses, e.g. "cauchy, then tukey (6)".
  int iterations = 0;
  bool converged = true;  // The final refinement stopped by a convergence test.
  // What went wrong on the way without stopping the calibration (a failed trimming, no
  // convergence, a log without inliers); also appended to observability.warnings.
  std::vector<std::string> warnings;
  // Why the numbers cannot be relied on although the fit ran (most intervals gross, the inliers
  // not determining the parameters); each also in `warnings`. Empty when none.
  std::vector<std::string> unreliable;
  double outlier_share = 0.0;  // GrossOutlierShare of the final residuals (outlier_share.h).
  // Per log, the boundary-stamp jitter estimated at the base fit (empty when not asked for), and
  // whether the result is the refit with it (then noise_sigma, is_inlier and the covariance are
  // the refit's, and the covariance a sandwich that keeps the neighbours' correlation).
  std::vector<IntervalJitterEstimate> interval_jitter;
  bool jitter_refit = false;
  double closed_form_seconds = 0.0;
  double refinement_seconds = 0.0;
  double covariance_seconds = 0.0;
};

StatusOr<LaserCalibrationResult> CalibrateLaser(const std::vector<LaserInterval>& intervals,
                                                const LaserCalibrationOptions& options = {});

// Several logs of the same robot calibrated jointly (shared parameters, each log with its own
// noise level), as the paper joins its datasets.
StatusOr<LaserCalibrationResult> CalibrateLaserJoint(
    const std::vector<const std::vector<LaserInterval>*>& logs,
    const LaserCalibrationOptions& options = {});

// Checks that intervals are usable (finite values, positive durations); the message names the
// first bad interval.
Status ValidateLaserIntervals(const std::vector<LaserInterval>& intervals);

}  // namespace calib

#endif  // CALIB_SOLVERS_LASER_CALIBRATE_LASER_H_
