#include <calib/solvers/scan_matching/scan_odometry.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace calib {

void ScanOdometry::StartChain(ScanPoints points, const Pose2d& world_T_sensor) {
  const int i = result_.size() - 1;
  keyframe_points_ = std::move(points);
  keyframe_ = i;
  result_.poses[i].world_T_sensor = world_T_sensor;
  result_.chain[i] = next_chain_++;
  result_.covariances[i].setZero();
  consecutive_failures_ = 0;
}

// Σ_current = J_k Σ_keyframe J_kᵀ + J_m Σ_match J_mᵀ for world_T_current = world_T_key ⊕ m.
Eigen::Matrix3d ScanOdometry::Propagate(const Pose2d& keyframe_T_current,
                                        const Eigen::Matrix3d& match_cov) const {
  const double theta = result_.poses[keyframe_].world_T_sensor(2);
  const double c = std::cos(theta);
  const double s = std::sin(theta);
  const double mx = keyframe_T_current(0);
  const double my = keyframe_T_current(1);
  Eigen::Matrix3d j_key;
  j_key << 1, 0, -s * mx - c * my, 0, 1, c * mx - s * my, 0, 0, 1;
  Eigen::Matrix3d j_match;
  j_match << c, -s, 0, s, c, 0, 0, 0, 1;
  return j_key * result_.covariances[keyframe_] * j_key.transpose() +
         j_match * match_cov * j_match.transpose();
}

Status ScanOdometry::AddScan(const LaserScan& scan, const Pose2d& previous_T_current_guess,
                             const std::optional<SweepMotion>& sweep) {
  const bool first = result_.poses.empty();
  if (!first && !previous_T_current_guess.allFinite()) {
    return Status::InvalidInput("scan odometry: the guess for scan " +
                                std::to_string(result_.size()) + " (record " +
                                std::to_string(scan.record) + ") is not finite");
  }
  const double inf = std::numeric_limits<double>::infinity();
  const Pose2d world_T_predicted =
      first ? options_.world_T_first_sensor
            : Compose(result_.poses.back().world_T_sensor, previous_T_current_guess);
  result_.poses.push_back({scan.stamp_s, world_T_predicted, static_cast<int>(scan.record)});
  result_.matches.emplace_back();
  result_.keyframe_of.push_back(-1);
  result_.covariances.push_back(Eigen::Vector3d(inf, inf, inf).asDiagonal());
  result_.chain.push_back(-1);
  const int i = result_.size() - 1;

  ScanPointsOptions points_options;
  points_options.sweep = sweep;
  StatusOr<ScanPoints> points = MakeScanPoints(scan, points_options);
  if (first) {
    StartChain(points.ok() ? std::move(points).value() : ScanPoints(), world_T_predicted);
    return Status::Ok();
  }
  ScanMatch& match = result_.matches[i];
  if (points.ok()) {
    const Pose2d& world_T_key = result_.poses[keyframe_].world_T_sensor;
    StatusOr<ScanMatch> matched = MatchScanPoints(
        keyframe_points_, *points, Between(world_T_key, world_T_predicted), options_.match);
    // The guess is finite here, so a failure can only come from the options: not the scan's fault.
    if (!matched.ok()) return matched.status();
    match = std::move(matched).value();
  } else {
    match.quality = ScanMatchQuality::kTooFewCorrespondences;
    match.reason = points.message();
  }
  if (!match.ok()) {
    result_.failed.push_back(i);
    // A scan with too few returns to match anything cannot start a chain either.
    if (++consecutive_failures_ >= options_.max_consecutive_failures && points.ok() &&
        points->NumPoints() >= options_.match.min_correspondences) {
      StartChain(std::move(points).value(), world_T_predicted);
    }
    return Status::Ok();
  }
  consecutive_failures_ = 0;
  result_.keyframe_of[i] = keyframe_;
  result_.poses[i].world_T_sensor =
      Compose(result_.poses[keyframe_].world_T_sensor, match.reference_T_current);
  result_.covariances[i] = Propagate(match.reference_T_current, match.covariance);
  result_.chain[i] = result_.chain[keyframe_];
  const Pose2d& motion = match.reference_T_current;
  const bool far = motion.head<2>().norm() > options_.keyframe_distance_m ||
                   std::abs(motion(2)) > options_.keyframe_angle_rad;
  const bool fading =
      match.correspondences < options_.keyframe_min_matched_fraction * points->NumPoints();
  if (far || fading) {
    keyframe_points_ = std::move(points).value();
    keyframe_ = i;
  }
  return Status::Ok();
}

StatusOr<ScanOdometryResult> RunScanOdometry(const std::vector<LaserScan>& scans,
                                             const std::vector<Pose2d>& guesses,
                                             const ScanOdometryOptions& options,
                                             const std::vector<SweepMotion>* sweeps) {
  if (!scans.empty() && guesses.size() + 1 != scans.size()) {
    return Status::InvalidInput("scan odometry: " + std::to_string(scans.size()) + " scans need " +
                                std::to_string(scans.size() - 1) + " guesses, got " +
                                std::to_string(guesses.size()));
  }
  if (sweeps != nullptr && sweeps->size() != scans.size()) {
    return Status::InvalidInput("scan odometry: one sweep motion per scan is needed");
  }
  ScanOdometry odometry(options);
  for (size_t i = 0; i < scans.size(); ++i) {
    std::optional<SweepMotion> sweep;
    if (sweeps != nullptr) sweep = (*sweeps)[i];
    CALIB_RETURN_IF_ERROR(
        odometry.AddScan(scans[i], i == 0 ? Pose2d::Zero() : guesses[i - 1], sweep));
  }
  return odometry.result();
}

}  // namespace calib
