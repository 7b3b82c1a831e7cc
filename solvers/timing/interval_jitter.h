#ifndef CALIB_SOLVERS_TIMING_INTERVAL_JITTER_H_
#define CALIB_SOLVERS_TIMING_INTERVAL_JITTER_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/laser/laser_params.h>

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

// Timing jitter on logs of intervals (tuple/CSV), which carry no raw odometry: the stamps at the
// interval boundaries are off by independent ε ~ N(0, σ_j²), so the wheel rotation attributed to
// interval k is off by φ(t_{k+1})·ε_{k+1} − φ(t_k)·ε_k, φ the wheel speeds at the boundaries
// (from the neighbouring intervals). Linearised through the prediction, the error of interval k is
//   e_k = n_k + g_k,start·ε_k + g_k,end·ε_{k+1},   n_k ~ N(0, diag σ_n²),
// so Σ_k = diag σ_n² + σ_j²·(g_s g_sᵀ + g_e g_eᵀ), and neighbours sharing a boundary correlate:
// Cov(e_k, e_{k+1}) = σ_j²·g_k,end·g_{k+1},startᵀ. The jitter part grows with the boundary speeds,
// the scan noise does not: that separates the two.
//
// The likelihood used here is the product of the per-interval marginals (the diagonal blocks):
// under σ_j = 0 the intervals are independent, so its scores are sums of independent terms and the
// likelihood-ratio test keeps its null distribution; away from it the estimates stay consistent.
// The refit whitens each interval by its own block; the neglected neighbour correlation is put back
// into the parameter covariance (JitterCrossCovariances, the refinement's sandwich).
namespace calib {

// Per-interval sensitivity of the predicted sensor displacement (as the error e = ŝ − ŝ_pred, in
// SensorMotionError's components) to the interval's start and end times: ∂ŝ/∂t.
struct IntervalTimeSensitivity {
  Eigen::Vector3d start = Eigen::Vector3d::Zero();
  Eigen::Vector3d end = Eigen::Vector3d::Zero();
};

// Wheel speeds (φ_l, φ_r) rad/s at each interval's start and end. At a boundary between two
// contiguous intervals, the linear interpolation between the neighbouring mean speeds (or the
// adjacent wheel steps when present) at the interval centres; after a gap or at the ends of the
// log, the interval's own.
struct IntervalBoundarySpeeds {
  Eigen::Vector2d start = Eigen::Vector2d::Zero();
  Eigen::Vector2d end = Eigen::Vector2d::Zero();
};
std::vector<IntervalBoundarySpeeds> BoundaryWheelSpeeds(
    const std::vector<LaserInterval>& intervals);

// g_start = ∂/∂ε [ℓ⁻¹ ∘ W(−φ_s·ε) ∘ o ∘ ℓ], g_end = ∂/∂ε [ℓ⁻¹ ∘ o ∘ W(φ_e·ε) ∘ ℓ] at ε = 0, with
// W the wheel-step displacement and o the interval's robot displacement.
std::vector<IntervalTimeSensitivity> IntervalTimeSensitivities(
    const std::vector<LaserInterval>& intervals, const LaserCalibration& calibration);
// The same for the intervals at `indices` only (one sensitivity per index).
std::vector<IntervalTimeSensitivity> IntervalTimeSensitivities(
    const std::vector<LaserInterval>& intervals, const LaserCalibration& calibration,
    const std::vector<size_t>& indices);
// The same with the intervals' BoundaryWheelSpeeds given (a refit's rounds share them).
std::vector<IntervalTimeSensitivity> IntervalTimeSensitivities(
    const std::vector<LaserInterval>& intervals, const std::vector<IntervalBoundarySpeeds>& speeds,
    const LaserCalibration& calibration);

// σ_j²·(g_s g_sᵀ + g_e g_eᵀ): what the jitter adds to one interval's error covariance.
Eigen::Matrix3d JitterCovariance(const IntervalTimeSensitivity& sensitivity, double jitter_s);

// Cov(e_k, e_{k+1}) = σ_j²·g_k,end·g_{k+1},startᵀ for each k (zero where interval k+1 follows a
// gap); size n − 1 (empty for n < 2).
std::vector<Eigen::Matrix3d> JitterCrossCovariances(
    const std::vector<LaserInterval>& intervals,
    const std::vector<IntervalTimeSensitivity>& sensitivities, double jitter_s);

// Per interval, the covariance σ_j²·(φ_s φ_sᵀ + φ_e φ_eᵀ) of the error of its wheel increments
// (Δφ_l, Δφ_r): the regressor noise whose attenuation bias LaserProblem::IncrementNoiseCorrection
// removes.
std::vector<Eigen::Matrix2d> JitterIncrementCovariances(const std::vector<LaserInterval>& intervals,
                                                        double jitter_s);
std::vector<Eigen::Matrix2d> JitterIncrementCovariances(
    const std::vector<IntervalBoundarySpeeds>& speeds, double jitter_s);

// Per interval, the upper-triangular L with LᵀL = Σ_k⁻¹, Σ_k = diag(σ_n²) + the jitter's part.
std::vector<Eigen::Matrix3d> JitterSqrtInformation(
    const std::vector<IntervalTimeSensitivity>& sensitivities, const Eigen::Vector3d& noise_sigma,
    double jitter_s);

// Per interval, e_kᵀΣ_k⁻¹e_k with Σ_k as above (‖L·e_k‖², by cofactors, without the root).
std::vector<double> JitterWhitenedSquaredNorms(
    const std::vector<Eigen::Vector3d>& errors,
    const std::vector<IntervalTimeSensitivity>& sensitivities, const Eigen::Vector3d& noise_sigma,
    double jitter_s);

struct IntervalJitterEstimate;

struct IntervalJitterOptions {
  // Level of the likelihood-ratio test against σ_j = 0.
  double significance = 0.01;
  // Re-estimate the scan noise jointly with σ_j (profile likelihood); false keeps it fixed.
  bool estimate_noise = true;
  // Points of the search over σ_j: 0, then a log grid of 4 decades (11: a step of 2.8×, the best
  // point's neighbours bracketing the maximum the joint scoring then finds; finer grids find the
  // same maximum on the real logs at twice the cost).
  int grid_points = 11;
  // Above this many inliers the likelihood runs on an evenly spread subset of this size (σ_j is
  // then known to a few per cent; the profile costs ~10³ 3×3 factorizations per interval).
  int max_intervals = 20000;
  // > 0: an estimate from a nearby fit (a refit's previous round). The maximum is then searched
  // within a factor of 3 of it, without the grid; the grid runs when it lies on that bracket's
  // edge.
  double previous_jitter_s = 0.0;
  // With previous_jitter_s: the scan noise σ (x, y, θ) estimated there (the previous round's). The
  // joint scoring then starts from it rather than profiling θ at previous_jitter_s first (two or
  // three passes fewer); zero: profiled.
  Eigen::Vector3d previous_noise_sigma = Eigen::Vector3d::Zero();
  // Refine the search's best σ_j by Fisher scoring jointly in (θ, σ_j²) (a few passes), falling
  // back to a golden-section search of the profile when that does not settle inside the bracket;
  // false: the golden section always (the reference the tests compare with).
  bool joint_scoring = true;
  // Whether σ of σ_j is wanted (from the joint scoring's observed information; without it, two
  // more profiles, a third of a refit round's passes), asked with the estimate otherwise
  // complete; empty: always. A refit wants it for its last round only.
  std::function<bool(const IntervalJitterEstimate&)> stddev_wanted;
};

struct IntervalJitterEstimate {
  double jitter_s = 0, jitter_stddev_s = 0;
  double lr_statistic = 0, p_value = 1;
  bool significant = false;
  // The scan noise σ (x, y, θ) estimated jointly at σ_j = jitter_s, and at σ_j = 0.
  Eigen::Vector3d noise_sigma = Eigen::Vector3d::Zero();
  Eigen::Vector3d noise_sigma_without_jitter = Eigen::Vector3d::Zero();
  double log_likelihood = 0, log_likelihood_without_jitter = 0;
  int intervals_used = 0;  // The inliers the likelihood was evaluated on (after any subsetting).
};

// σ_j by profile likelihood over the inliers' errors e_k: ℓ(σ_j) = max over σ_n of
// −½Σ[log det Σ_k + e_kᵀΣ_k⁻¹e_k] on a grid, refined by golden section; the LR test against σ_j = 0
// (on the boundary: ½χ²₀ + ½χ²₁); σ of σ_j from the profile's curvature (the joint scoring's
// observed information where it found the maximum, else differences). `noise_sigma` starts
// the noise re-estimation (or is kept with estimate_noise = false).
// The intervals the estimate uses: every stride-th inlier, so that at most about
// `max_intervals` remain (the stride the smallest that does).
std::vector<size_t> JitterSampleIndices(size_t n, const std::vector<bool>& is_inlier,
                                        int max_intervals);

IntervalJitterEstimate EstimateIntervalJitter(
    const std::vector<Eigen::Vector3d>& errors,
    const std::vector<IntervalTimeSensitivity>& sensitivities, const Eigen::Vector3d& noise_sigma,
    const std::vector<bool>& is_inlier, const IntervalJitterOptions& options = {});

// The same from the intervals and a calibration (errors and sensitivities computed at it; the
// errors taken from `errors` instead when given: every interval's, at `calibration`).
IntervalJitterEstimate EstimateIntervalJitter(const std::vector<LaserInterval>& intervals,
                                              const LaserCalibration& calibration,
                                              const Eigen::Vector3d& noise_sigma,
                                              const std::vector<bool>& is_inlier,
                                              const IntervalJitterOptions& options = {},
                                              const std::vector<Eigen::Vector3d>* errors = nullptr);

// The output's sentence: only the weaker treatment was possible on these intervals.
std::string IntervalJitterStatement(const IntervalJitterEstimate& estimate);

}  // namespace calib

#endif  // CALIB_SOLVERS_TIMING_INTERVAL_JITTER_H_
