#ifndef CALIB_SOLVERS_SCAN_MATCHING_SCAN_ODOMETRY_H_
#define CALIB_SOLVERS_SCAN_MATCHING_SCAN_ODOMETRY_H_

#include <calib/core/laser/laser_log.h>
#include <calib/core/scan/laser_scan.h>
#include <calib/core/se2.h>
#include <calib/core/status.h>
#include <calib/solvers/scan_matching/pl_icp.h>
#include <calib/solvers/scan_matching/scan_points.h>

#include <Eigen/Core>
#include <optional>
#include <vector>

// Scan odometry with keyframes: every scan is matched against the last keyframe (not against the
// previous scan), so a robot at rest accumulates no drift. A scan whose match fails its quality
// check becomes a gap: it belongs to no chain and its pose is only dead-reckoned from the guesses.
namespace calib {

struct ScanOdometryOptions {
  PlIcpOptions match;
  // A matched scan becomes the next keyframe when it is this far from the current one...
  double keyframe_distance_m = 0.3;
  double keyframe_angle_rad = 0.3;
  // ...or when its match kept less than this fraction of its returns (the overlap is fading).
  double keyframe_min_matched_fraction = 0.6;
  // After this many failed matches in a row the latest scan starts a new chain as its keyframe.
  int max_consecutive_failures = 3;
  Pose2d world_T_first_sensor = Pose2d::Zero();
};

struct ScanOdometryResult {
  // world_T_sensor of every scan (t_s = stamp, line = the scan's record); a failed scan's pose is
  // the previous pose composed with its guess.
  std::vector<StampedPose> poses;
  std::vector<ScanMatch> matches;  // Scan i against keyframe_of[i] (default for chain starts).
  std::vector<int> keyframe_of;    // −1 where no match was made (the first scan, chain starts).
  // Of world_T_sensor relative to its chain's first scan, propagated through the keyframes.
  std::vector<Eigen::Matrix3d> covariances;
  // The chain each scan belongs to; −1 for a failed scan. Poses in one chain are linked by scan
  // matching; across chains (or through a −1) only by the guesses.
  std::vector<int> chain;
  std::vector<int> failed;  // Indices of the scans whose match failed (the gaps).

  int size() const { return static_cast<int>(poses.size()); }
  // True when scans i and i+1 are linked by scan matching (a valid interval).
  bool PairIsValid(int i) const {
    return i >= 0 && i + 1 < size() && chain[i] >= 0 && chain[i] == chain[i + 1];
  }
};

class ScanOdometry {
 public:
  explicit ScanOdometry(ScanOdometryOptions options = {}) : options_(options) {}

  // Adds the next scan with the predicted sensor displacement previous_T_current since the
  // previous scan (ignored for the first) and, optionally, the sensor's motion during its sweep
  // for de-skewing. Fails only on a non-finite guess or bad options; a malformed or unmatched
  // scan becomes a gap.
  Status AddScan(const LaserScan& scan, const Pose2d& previous_T_current_guess,
                 const std::optional<SweepMotion>& sweep = std::nullopt);

  const ScanOdometryResult& result() const { return result_; }

 private:
  void StartChain(ScanPoints points, const Pose2d& world_T_sensor);
  Eigen::Matrix3d Propagate(const Pose2d& keyframe_T_current,
                            const Eigen::Matrix3d& match_cov) const;

  ScanOdometryOptions options_;
  ScanOdometryResult result_;
  ScanPoints keyframe_points_;
  int keyframe_ = -1;
  int next_chain_ = 0;
  int consecutive_failures_ = 0;
};

// Runs ScanOdometry over `scans` with previous_T_current guesses (one per consecutive pair:
// guesses[i] leads from scan i to scan i + 1) and optional per-scan sweep motions.
StatusOr<ScanOdometryResult> RunScanOdometry(const std::vector<LaserScan>& scans,
                                             const std::vector<Pose2d>& guesses,
                                             const ScanOdometryOptions& options = {},
                                             const std::vector<SweepMotion>* sweeps = nullptr);

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_MATCHING_SCAN_ODOMETRY_H_
