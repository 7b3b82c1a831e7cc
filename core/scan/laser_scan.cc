#include <calib/core/scan/laser_scan.h>

#include <cmath>

namespace calib {

int AssumeRotationPeriod(double rotation_period_s, std::vector<LaserScan>* scans) {
  int given = 0;
  for (LaserScan& scan : *scans) {
    if (scan.time_increment_s != 0.0) continue;
    scan.time_increment_s = rotation_period_s * std::abs(scan.angle_increment_rad) / (2.0 * M_PI);
    given += scan.time_increment_s != 0.0;
  }
  return given;
}

}  // namespace calib
