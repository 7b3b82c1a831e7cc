#ifndef CALIB_SOLVERS_BEARING_CALIBRATE_BEARING_H_
#define CALIB_SOLVERS_BEARING_CALIBRATE_BEARING_H_

#include <calib/core/bearing/bearing_log.h>
#include <calib/core/bearing/bearing_model.h>
#include <calib/core/status.h>
#include <calib/solvers/bearing/bearing_bundle_adjustment.h>
#include <calib/solvers/bearing/bearing_seed_search.h>
#include <calib/solvers/bearing/bearing_timing.h>
#include <calib/solvers/bearing/martinelli_closed_form.h>

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <vector>

// Bearing-only calibration in one call (Martinelli 2009): seed → bundle adjustment with the noise
// levels estimated from the data → covariance.
//
//   calib::StatusOr<calib::BearingLog> log = calib::ReadBearingLog("run_dir");
//   calib::StatusOr<calib::BearingCalibrationResult> result = calib::CalibrateBearing(*log);
//   if (result.ok()) use(result->estimate, result->stddev);
//
// Seed. When the log holds circular runs at three or more distinct q = vL/vR, Martinelli's closed
// form on those runs (solvers/bearing/martinelli_closed_form.h); otherwise, or when the adjustment
// from it does not explain the bearings, a coarse search (SearchBearingSeed,
// solvers/bearing/bearing_seed_search.h) that handles arbitrary trajectories. Each run's start is
// then placed from the seed calibration by a linear fit of the landmark's position to its
// bearings (SeedLandmarks), and its poses at the bearing times by dead reckoning. Both seeds are
// least squares: bearings that disagree with their neighbours in time (gross outliers) are left out
// of them. A seed is accepted when the adjustment from it leaves residuals no larger than twice the
// neighbours' own scatter; if none is, the log is rejected.
//
// Noise. σβ and the encoder constant K are unknown to the log; unless given they are estimated
// by variance components: σβ² = Σe²/Σ(1 − h) over the inlier bearings (h the leverages, corrected
// for the inlier cut), K² ← K²·Σ‖L·e‖²/Σ(3 − tr h) over the odometry terms, re-solving between
// rounds. K rests on the few degrees of freedom the bearings leave to the odometry (about
// ½√(q/r) per bearing, q and r the per-step odometry and bearing variances: a dozen on the §8.1
// runs), so it is only as good as that count r_o allows. It is therefore taken one-sided,
// K = max(K_floor, K̂) (BearingCalibrationOptions::encoder_noise_k_floor), and when the data
// raise it, the covariance takes K at the upper end of its one-sigma range, K̂²·(1 + √(2/r_o)).
//
// Timing (solvers/bearing/bearing_timing.h). After the noise levels, the clock offset τ between
// bearings and encoders is estimated with the adjustment (a likelihood-ratio test against τ = 0,
// at the level BearingTimingOptions::significance, the loss's scale counted); when it is
// significant the calibration is the fit with τ, its noise levels re-estimated. Then the stamp
// jitter σ_t by profile likelihood on the bearing errors and rates (test against σ_t = 0); when it
// is significant each bearing is whitened by √(σβ² + σ_t²·(dβ̂/dt)²) and the fit re-solved (K kept).
// When neither test rejects, the result is the plain fit's, bit for bit.
//
// Covariance. ceres::Covariance on the calibration block (the poses are nuisance), corrected for
// the robust loss (BearingProblem::Covariance); with an initial distance, also on D0' and mapped
// to the metric set by BearingMetricFromScaled.
namespace calib {

struct BearingCalibrationOptions {
  BearingAdjustmentOptions adjustment;
  MartinelliOptions closed_form;
  BearingSearchOptions search;
  bool use_closed_form = true;  // Try the closed-form seed first when the runs allow it.
  BearingTimingOptions timing;  // The clock offset and stamp jitter (both tested by default).
  // Known noise levels; estimated from the data when empty.
  std::optional<double> bearing_sigma_rad;
  std::optional<double> encoder_noise_k;
  // K is estimated from the data but not below this floor (m^½). The data hold few degrees of
  // freedom for K (see above) and its estimate can collapse towards 0, which would make the
  // sigmas of δ (the parameter the encoder noise limits) too small; the floor is Martinelli's
  // Table 1 value, about twice that of real encoders (Chong and Kleeman), so conservative.
  double encoder_noise_k_floor = 1e-3;
  int noise_rounds = 6;           // At most this many re-solves for the noise levels.
  double noise_tolerance = 0.03;  // ... while a level changes by more than this.
  // Bearings whose squared whitened residual exceeds this are outliers (χ²₁ at 99.9 %).
  double inlier_chi2 = 10.83;
  // Seeding leaves out bearings that miss a quadratic through their neighbours in time by more
  // than this many times the neighbours' scatter, and by 2° at least (the adjustment keeps them,
  // under its loss).
  double seed_outlier_cut = 5.0;
  // A seed is rejected (and the next one tried) when the adjustment from it leaves residuals
  // whose robust scale exceeds this many times the neighbours' scatter: a wrong minimum.
  double max_fit_over_scatter = 2.0;
  // Larger standard deviations flag a poorly determined parameter (a warning with its σ; the
  // estimate is still returned): angles (rad), and η, δ, ξ relative to their value.
  double max_angle_stddev_rad = 0.1;
  double max_relative_stddev = 0.1;
  // Beyond these the log does not determine the parameter at all (not even its sign or
  // quadrant): an error, not a number.
  double undetermined_angle_stddev_rad = 1.0;
  double undetermined_relative_stddev = 0.5;
  std::function<void(const std::string&)> progress;  // Optional progress lines.
  // Refuse an estimate that reads the wheels wrongly (a sign, swapped columns, another unit:
  // bearing_input_checks.h).
  bool check_readings = true;
};

// Where the adjustment started: Martinelli's closed form (circular runs) or the coarse search
// (any trajectory).
enum class BearingSeedMethod { kNone, kClosedForm, kSearch };
// "closed_form", "search" ("" for kNone): the report's words.
const char* SeedMethodName(BearingSeedMethod method);

struct BearingRunSummary {
  int run = 0;
  int bearings = 0;
  int inliers = 0;
  bool circular = false;        // Used by the closed form as a circle at fixed q.
  double q = 0.0;               // vL/vR of a circular run.
  double start_distance = 0.0;  // Robot–landmark distance at the run's start, gauge units (δR m).
  double rms_residual_rad = 0.0;  // Of its inlier bearings.
};

struct BearingCalibrationResult {
  BearingParams estimate;  // φ, ψ, η, δ, ξ.
  BearingParamMatrix covariance = BearingParamMatrix::Zero();
  BearingParamVector stddev = BearingParamVector::Zero();
  // With an initial distance: the metric set and its covariance (φ, ψ, ρ, δR, δL, δB).
  bool has_metric = false;
  BearingMetricParams metric;
  BearingMetricMatrix metric_covariance = BearingMetricMatrix::Zero();
  BearingMetricVector metric_stddev = BearingMetricVector::Zero();

  BearingSeedMethod seed_method = BearingSeedMethod::kNone;
  BearingParams seed;
  bool has_closed_form = false;
  MartinelliEstimate closed_form;
  std::string closed_form_message;   // Why the closed form was not used, when it was not.
  int seed_excluded = 0;             // Bearings left out of the seeds (they miss their neighbours).
  double bearing_scatter_rad = 0.0;  // σβ as the neighbours in time see it (CheckConsistency).

  bool has_seed_metric = false;  // With an initial distance: the seed's metric set.
  BearingMetricParams seed_metric;

  BearingNoise noise;               // The noise levels of the estimate.
  double encoder_k_estimate = 0.0;  // The variance-component value of K (0: too few dof).
  double covariance_encoder_k = 0;  // K used for the covariance (see below).
  bool bearing_sigma_estimated = false;
  bool encoder_k_estimated = false;
  double bearing_redundancy = 0.0;
  double odometry_redundancy = 0.0;
  int noise_rounds = 0;

  int samples = 0;  // Bearings.
  int inliers = 0;
  std::vector<BearingRunSummary> runs;
  std::vector<std::vector<double>> residuals_rad;  // Per run, per bearing: wrap(β − β̂).
  std::vector<std::vector<Pose2d>> poses;          // Per run, at its nodes (gauge units).
  std::vector<std::vector<double>> node_times_s;   // Per run, the times of those nodes.
  std::vector<std::vector<bool>> is_inlier;        // Per run, per bearing: within the cut.
  double covariance_scale = 1.0;                   // κ.
  int iterations = 0;
  bool converged = true;  // The final adjustment stopped by a convergence test.
  std::string loss;       // The adjustment's losses, e.g. "cauchy, then tukey (6)".
  // What the calibration modelled of the timing (τ with σ, the stamp jitter; see above).
  BearingTiming timing;
  // What went wrong on the way without stopping the calibration (e.g. no convergence).
  std::vector<std::string> warnings;
  // Why the numbers cannot be relied on although the fit ran (most bearings gross); each also in
  // `warnings`. Empty when none.
  std::vector<std::string> unreliable;
  double outlier_share = 0.0;  // GrossOutlierShare of the final bearing residuals.
  double seed_seconds = 0.0;
  double adjustment_seconds = 0.0;
  double covariance_seconds = 0.0;
};

// Validates the log once (ValidateBearingLog); the steps below take it as valid.
StatusOr<BearingCalibrationResult> CalibrateBearing(const BearingLog& log,
                                                    const BearingCalibrationOptions& options = {});

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_CALIBRATE_BEARING_H_
