#include <calib/core/laser/wheel_profile.h>

namespace calib {
namespace laser_sim_internal {
namespace {

// A commanded wheel-speed target for the trajectory kind.
Eigen::Array2d DrawTarget(LaserTrajectory kind, double max_speed, Random* random) {
  // Magnitudes of at least a fifth of the maximum keep every segment informative.
  const auto magnitude = [&] { return random->Sign() * random->Uniform(0.2, 1.0) * max_speed; };
  switch (kind) {
    case LaserTrajectory::kStraight: {
      const double s = magnitude();
      return Eigen::Array2d(s, s);
    }
    case LaserTrajectory::kPureRotation: {
      const double s = magnitude();
      return Eigen::Array2d(-s, s);
    }
    case LaserTrajectory::kConstantArc:
      return Eigen::Array2d(0.6, 1.0) * max_speed;
    case LaserTrajectory::kRich:
      break;
  }
  const double choice = random->Uniform();
  const double s = magnitude();
  if (choice < 1.0 / 3.0) return Eigen::Array2d(s, s);
  if (choice < 2.0 / 3.0) return Eigen::Array2d(-s, s);
  // An arc: the faster wheel at s, the other anywhere in [−|s|, |s|] (curvature of either sign).
  const double other = s * random->Uniform(-1.0, 1.0);
  return random->Uniform() < 0.5 ? Eigen::Array2d(s, other) : Eigen::Array2d(other, s);
}

}  // namespace

WheelProfile ConstantSpeedProfile(const LaserSimOptions& options,
                                  const std::vector<double>& boundaries, Random* targets) {
  Random& random = *targets;
  std::vector<SpeedSegment> segments;
  const double hold_mean = std::max(options.segment_mean_s, 0.0);
  double next_change = 0.0;
  for (size_t k = 0; k + 1 < boundaries.size(); ++k) {
    const double t = boundaries[k];
    if (k > 0 && t < next_change) continue;
    const Eigen::Array2d target = DrawTarget(options.trajectory, options.max_wheel_speed, &random);
    next_change = t + random.Exponential(hold_mean);
    if (!segments.empty()) {
      const SpeedSegment& last = segments.back();
      if ((target == last.target).all()) continue;
      SpeedSegment segment;
      segment.start_s = t;
      segment.angle = last.angle + last.target * (t - last.start_s);
      segment.target = segment.speed = target;
      segments.push_back(segment);
    } else {
      SpeedSegment segment;
      segment.target = segment.speed = target;
      segments.push_back(segment);
    }
  }
  return WheelProfile(0.0, std::move(segments));
}

WheelProfile SmoothProfile(const LaserSimOptions& options, double end_s, Random* targets) {
  Random& random = *targets;
  const double tau = options.speed_time_constant_s;
  const double hold_mean =
      options.segment_mean_s > 0.0 ? options.segment_mean_s : options.mean_interval_s;
  std::vector<SpeedSegment> segments(1);
  segments[0].target = segments[0].speed =
      DrawTarget(options.trajectory, options.max_wheel_speed, &random);
  const WheelProfile evaluator(tau, {});
  if (options.trajectory == LaserTrajectory::kConstantArc) {
    return WheelProfile(tau, std::move(segments));
  }
  double start = random.Exponential(hold_mean);
  while (start < end_s) {
    const SpeedSegment& last = segments.back();
    SpeedSegment segment;
    segment.start_s = start;
    segment.speed = evaluator.Speed(last, start - last.start_s);
    segment.angle = last.angle + evaluator.Rotation(last, start - last.start_s);
    segment.target = DrawTarget(options.trajectory, options.max_wheel_speed, &random);
    segments.push_back(segment);
    start += random.Exponential(hold_mean);
  }
  return WheelProfile(tau, std::move(segments));
}

}  // namespace laser_sim_internal
}  // namespace calib
