#ifndef CALIB_SOLVERS_LASER_LASER_CONSISTENCY_H_
#define CALIB_SOLVERS_LASER_LASER_CONSISTENCY_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/laser/laser_params.h>

#include <Eigen/Core>
#include <string>
#include <vector>

// A timing-free check of a laser–odometry calibration: over long windows, the rotation and the
// travel that the calibrated wheel model predicts from the TOTAL wheel rotation against what the
// sensor measured,
//   rotation:  Σ (r_r·Δφ_r − r_l·Δφ_l)/b      vs  Σ sm_θ,
//   travel:    Σ (r_l·Δφ_l + r_r·Δφ_r)/2      vs  Σ forward arc length of o = ℓ ∘ sm ∘ ℓ⁻¹.
// Both sides are sums over intervals, so they do not depend on how the wheel rotation is split
// between intervals (on the timing of the samples) except at the window ends and at excluded
// intervals. A per-interval least squares fed with stamps that are not sample times is biased
// (errors in the regressors); these totals are not, so a disagreement exposes it, as it exposes a
// wheel slip or wheel rotation in the wrong units.
//
// Only inlier intervals enter the sums (outliers are scan-match failures or slips), and the fit's
// outliers whose sum with a neighbour agrees (a misplaced stamp, not a failure). The σ of the
// difference accounts for the serial correlation of the per-interval differences (a Bartlett
// long-run variance with Andrews' automatic lag: poses from a scan matcher telescope) and for the
// estimate having been fitted to the same data (its influence function, so the σ is not the
// quadrature sum of the two sides' σ), plus the timing at the window ends (rate × period/√12).
// The tests are Holm-corrected together at the family-wise level of one two-sided 3σ test.
namespace calib {

struct LaserConsistencyOptions {
  // Family-wise false-alarm level over all windows and both quantities (two-sided 3σ).
  double family_alpha = 0.0027;
  // Windows between rests with fewer inlier intervals are not tested on their own.
  int min_window_intervals = 30;
  // σ of the time by which a window end may be misplaced, as a fraction of the interval period
  // (1/√12: a stamp anywhere within a period).
  double end_timing_fraction = 0.29;
  // At most this many warnings (the most significant windows); the JSON lists every window.
  int max_warnings = 3;
  // The per-interval passes run on this many threads (a million intervals: a second on one).
  int num_threads = 2;
};

// One side-by-side total: predicted by the wheel model, measured by the sensor.
struct LaserConsistencyTotal {
  double predicted = 0.0;        // rad or m.
  double measured = 0.0;         // rad or m.
  double sigma_predicted = 0.0;  // From the parameter covariance.
  double sigma_measured = 0.0;   // Long-run σ of the per-interval differences over the window.
  double sigma_ends = 0.0;       // Timing at the window ends and around excluded intervals.
  double sigma = 0.0;        // Of measured − predicted, all of the above with the fit's share.
  double z = 0.0;            // (measured − predicted)/σ.
  double p_value = 1.0;      // Two-sided.
  bool significant = false;  // Rejected by Holm at the family level.
};

struct LaserConsistencyWindow {
  int log = 0;       // Index of the log (joint calibration), 0-based.
  std::string kind;  // "run" (between gaps) or "between rests".
  int first = 0;     // First and last interval of the window, 0-based, inclusive.
  int last = 0;
  int intervals = 0;     // Inlier intervals summed.
  double start_s = 0.0;  // Time span (odometry clock, or summed T without stamps).
  double end_s = 0.0;
  LaserConsistencyTotal rotation;     // rad.
  LaserConsistencyTotal translation;  // m.
};

struct LaserConsistency {
  bool checked = false;  // False: not enough data or no covariance (`note` says why).
  std::string note;
  int tests = 0;         // Hypotheses in the family (two per window).
  int rotation_lag = 0;  // Bartlett lags of the long-run variances (Andrews' AR(1) rule).
  int translation_lag = 0;
  std::vector<LaserConsistencyWindow> windows;
  std::vector<std::string> warnings;  // One sentence each for a person.
};

// One log. `noise_sigma` is the scan noise (x, y, θ) that weighted the fit; `is_inlier` one flag
// per interval (empty: all inliers); `covariance` of the six parameters (a parameter with zero
// variance is treated as held fixed).
LaserConsistency CheckLaserConsistency(const std::vector<LaserInterval>& intervals,
                                       const LaserCalibration& estimate,
                                       const LaserParamMatrix& covariance,
                                       const Eigen::Vector3d& noise_sigma,
                                       const std::vector<bool>& is_inlier,
                                       const LaserConsistencyOptions& options = {});

// Several logs sharing the parameters (CalibrateLaserJoint): one noise level and one inlier
// vector per log; windows never span two logs.
LaserConsistency CheckLaserConsistencyJoint(
    const std::vector<const std::vector<LaserInterval>*>& logs, const LaserCalibration& estimate,
    const LaserParamMatrix& covariance, const std::vector<Eigen::Vector3d>& noise_sigma,
    const std::vector<std::vector<bool>>& is_inlier, const LaserConsistencyOptions& options = {});

}  // namespace calib

#endif  // CALIB_SOLVERS_LASER_LASER_CONSISTENCY_H_
