#ifndef CALIB_SOLVERS_SCAN_MATCHING_PL_ICP_H_
#define CALIB_SOLVERS_SCAN_MATCHING_PL_ICP_H_

#include <calib/core/scan/laser_scan.h>
#include <calib/core/se2.h>
#include <calib/core/status.h>
#include <calib/solvers/scan_matching/correspondences.h>
#include <calib/solvers/scan_matching/scan_points.h>

#include <Eigen/Core>
#include <string>

// Point-to-line ICP (Censi, "An ICP variant using a point-to-line metric", ICRA 2008): each current
// point is pulled onto the line through the reference points on either side of its nearest one
// (Correspondence::line_a/line_b), and the pose minimises Σ (nᵢ·(R pᵢ + t − qᵢ))² with the lines
// fixed, then the correspondences are searched again.
namespace calib {

enum class ScanMatchQuality {
  kOk,
  kTooFewCorrespondences,
  kDegenerate,  // The geometry leaves a direction (nearly) unconstrained, e.g. a corridor.
  kLargeResidual,
  kNotConverged,
};

const char* ScanMatchQualityName(ScanMatchQuality quality);

struct ScanMatch {
  Pose2d reference_T_current = Pose2d::Zero();
  // Of (x, y, θ): Censi's closed form Σ = H⁻¹ (Σₖ gₖ gₖᵀ σ̂²) H⁻¹ over every range zₖ that enters
  // the cost (gₖ = ∂∇J/∂zₖ, so points shared by several residuals count once), with the range
  // noise σ̂ estimated from the residuals. Infinite on the diagonal when nothing was matched.
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  int correspondences = 0;      // Inliers used in the final solve.
  double rms_residual_m = 0.0;  // Of the inliers' point-to-line distances.
  double range_sigma_m = 0.0;   // σ̂: the range noise the residuals imply (robust, MAD).
  // λmin/λmax of the information matrix with θ scaled by the points' RMS range (a length).
  double information_ratio = 0.0;
  int iterations = 0;
  bool converged = false;
  ScanMatchQuality quality = ScanMatchQuality::kOk;
  std::string reason;  // One sentence; empty when quality is ok.

  bool ok() const { return quality == ScanMatchQuality::kOk; }
};

struct PlIcpOptions {
  CorrespondenceOptions correspondence;
  ScanPointsOptions reference_points;  // De-skewing of each scan (used by MatchScans only).
  ScanPointsOptions current_points;
  int max_iterations = 40;
  // Converged when the correspondences repeat, or the step falls below these, or below
  // step_tolerance_sigmas standard deviations of the pose (σ²H⁻¹ with σ² the mean squared
  // residual; 0 turns this off).
  double step_tolerance_m = 1e-9;
  double step_tolerance_rad = 1e-10;
  double step_tolerance_sigmas = 0.1;
  // Until the pose settles only about this many of the current points are matched (every k-th);
  // 0 matches all of them from the start.
  int coarse_points = 360;
  // Residuals beyond outlier_sigmas·σ̂ are dropped; then the worst trim_fraction of the rest.
  // Both apply once a step has fallen below settle_step_m and settle_step_rad.
  double outlier_sigmas = 3.0;
  double trim_fraction = 0.0;
  double settle_step_m = 1e-3;
  double settle_step_rad = 1e-3;
  // Removes from the final pose the second-order bias that the range noise of both scans puts in
  // the point-to-line estimate (errors in variables; line_noise_bias.h).
  bool correct_noise_bias = true;
  // Quality checks.
  int min_correspondences = 20;
  double min_matched_fraction = 0.25;  // Of the current scan's returns.
  double min_information_ratio = 1e-2;
  double max_rms_residual_m = 0.05;
};

// Matches `current` against `reference` from the guess reference_T_current (e.g. odometry).
// Fails only on malformed input (non-finite guess or options, malformed scans); a match that
// fails its quality check comes back with quality != kOk and its reason.
StatusOr<ScanMatch> MatchScans(const LaserScan& reference, const LaserScan& current,
                               const Pose2d& reference_T_current_guess,
                               const PlIcpOptions& options = {});

// The same on scans already turned into points (lets a caller reuse a keyframe's points).
StatusOr<ScanMatch> MatchScanPoints(const ScanPoints& reference, const ScanPoints& current,
                                    const Pose2d& reference_T_current_guess,
                                    const PlIcpOptions& options = {});

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_MATCHING_PL_ICP_H_
