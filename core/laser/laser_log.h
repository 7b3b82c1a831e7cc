#ifndef CALIB_CORE_LASER_LASER_LOG_H_
#define CALIB_CORE_LASER_LASER_LOG_H_

#include <calib/core/diff_drive.h>
#include <calib/core/encoder_sample.h>
#include <calib/core/se2.h>
#include <calib/core/timing/stamp_timing.h>

#include <Eigen/Core>
#include <algorithm>
#include <string>
#include <vector>

namespace calib {

// One sample of the laser–odometry problem: over an interval of `duration_s` the wheels turn at
// mean speeds (left_speed, right_speed) rad/s, and the scan matcher reports the sensor
// displacement `sensor_motion` = ℓ⁻¹ ∘ o ∘ ℓ, expressed in the sensor frame at the start.
struct LaserInterval {
  double start_s = 0.0;  // Interval start on the odometry clock.
  double duration_s = 0.0;
  double left_speed = 0.0;   // φ_l, rad/s.
  double right_speed = 0.0;  // φ_r, rad/s.
  Pose2d sensor_motion = Pose2d::Zero();
  // Optional finer wheel profile within the interval (sums to duration and φ·T); empty means
  // constant speeds over the interval.
  std::vector<WheelStep> steps;
  bool gap_before = false;  // True when time jumps between the previous interval and this one.
  int line = 0;             // 1-based line of the source where the record starts (0: none).
  int record = 0;           // 1-based record number in the source.
};

// Raw streams: cumulative wheel rotations (rad, positive forward) on the odometry clock, and
// sensor poses in any fixed world frame from a scan matcher or lidar odometry.
struct StampedPose {
  double t_s = 0.0;
  Pose2d world_T_sensor = Pose2d::Zero();
  int line = 0;  // 1-based line in sensor_poses.csv (0: not from a file).
  // Poses of different segments are not linked (a scan matcher's chain broke between them): no
  // interval spans two segments.
  int segment = 0;
};

// The raw samples of a stream directory (declared with its reader in laser_log_io.h; defined
// here because LaserLog carries them).
struct LaserStreams {
  std::vector<EncoderSample> odometry;
  std::vector<StampedPose> sensor_poses;
};

struct LaserLog {
  std::string source;           // File name, for messages.
  bool has_timestamps = false;  // True when start_s came from the input, not from summing T.
  std::vector<LaserInterval> intervals;
  // From raw streams only (empty for tuples and CSV): the deduplicated, validated samples the
  // intervals were built from, and the timing diagnostics of each stream ("odometry",
  // "sensor_poses").
  LaserStreams streams;
  std::vector<StreamTiming> stream_timing;
  // What the reader corrected on the way, one sentence each (exact duplicate records dropped,
  // wrapped wheel angles unwrapped); the numbers are right, but the user should know.
  std::vector<std::string> warnings;
};

// The robot displacement over an interval for the given odometry parameters.
template <typename T>
Pose2<T> IntervalRobotMotion(const T& left_radius, const T& right_radius, const T& wheelbase,
                             const LaserInterval& interval) {
  if (interval.steps.empty()) {
    return WheelStepDisplacement(left_radius, right_radius, wheelbase,
                                 T(interval.left_speed * interval.duration_s),
                                 T(interval.right_speed * interval.duration_s));
  }
  return IntegrateWheelSteps(left_radius, right_radius, wheelbase, interval.steps);
}

// Every `stride`-th interval from the first: an evenly spread subset (stride 0 counts as 1).
inline std::vector<LaserInterval> EveryNthInterval(const std::vector<LaserInterval>& intervals,
                                                   size_t stride) {
  stride = std::max<size_t>(stride, 1);
  std::vector<LaserInterval> subset;
  subset.reserve((intervals.size() + stride - 1) / stride);
  for (size_t k = 0; k < intervals.size(); k += stride) subset.push_back(intervals[k]);
  return subset;
}

}  // namespace calib

#endif  // CALIB_CORE_LASER_LASER_LOG_H_
