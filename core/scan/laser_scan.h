#ifndef CALIB_CORE_SCAN_LASER_SCAN_H_
#define CALIB_CORE_SCAN_LASER_SCAN_H_

#include <cstdint>
#include <string>
#include <vector>

// One sweep of a 2D range finder, as sensor_msgs/LaserScan carries it. Beam i points at
// angle_min_rad + i·angle_increment_rad in the sensor frame (x forward, y left, counter-clockwise)
// and was measured at stamp_s + i·time_increment_s (the ROS convention: the stamp is the first
// beam's time; time_increment_s = 0 when the driver does not say).
namespace calib {

struct LaserScan {
  double stamp_s = 0.0;
  double angle_min_rad = 0.0;
  double angle_increment_rad = 0.0;
  double time_increment_s = 0.0;
  double scan_time_s = 0.0;  // Between two sweeps; 0 when unknown.
  double range_min_m = 0.0;
  double range_max_m = 0.0;
  // A range outside [range_min_m, range_max_m], or not finite, is no return.
  std::vector<float> ranges_m;
  std::vector<float> intensities;  // Empty or one per beam.
  std::string frame_id;
  // Where it came from, for messages: the record's index in its bag or its line in a CSV.
  int64_t record = 0;
  // The bag's log (receive) time of the message, when it came from a bag; else equal to stamp_s.
  double log_time_s = 0.0;

  double BeamAngle(int i) const { return angle_min_rad + i * angle_increment_rad; }
  double BeamTime(int i) const { return stamp_s + i * time_increment_s; }
  // From the first beam's time to the last's, (n − 1)·time_increment_s (negative for a scan whose
  // beams run backwards in time, e.g. mirrored).
  double SweepSeconds() const {
    return ranges_m.empty() ? 0.0 : time_increment_s * (static_cast<double>(ranges_m.size()) - 1.0);
  }
  bool IsReturn(int i) const {
    const float r = ranges_m[i];
    return r == r && r >= range_min_m && r <= range_max_m && r < 1e30f;
  }
};

// Beam times for the scans whose driver gave none (time_increment 0), from the lidar's rotation
// period: a spinning lidar turns through each angle_increment in period·|angle_increment|/2π,
// whatever its field of view. Returns how many scans were given them.
int AssumeRotationPeriod(double rotation_period_s, std::vector<LaserScan>* scans);

}  // namespace calib

#endif  // CALIB_CORE_SCAN_LASER_SCAN_H_
