#ifndef CALIB_CORE_SCAN_SELF_RETURNS_H_
#define CALIB_CORE_SCAN_SELF_RETURNS_H_

#include <calib/core/scan/laser_scan.h>

#include <string>
#include <utility>
#include <vector>

// Beams that see the robot itself (a mast's posts, a wheel guard, the chassis behind a 270°
// lidar): their returns stay at one short range in scan after scan while the scene around them
// moves. Matched, such points say the sensor did not move and pull every displacement toward
// zero (on a simulated log with 11 % of its beams on the body, d² 30 over the six parameters).
namespace calib {

struct SelfReturnOptions {
  double max_range_m = 1.0;      // No robot body is farther from its lidar.
  double return_share = 0.5;     // A beam must return in this share of the scans...
  double steady_share = 0.9;     // ...this share of them within the tolerance of its median...
  double tolerance_m = 0.03;     // ...this close (or 2 % of the range, the larger).
  // The scene must move: beams beyond max_range_m that stay put must be fewer than this share
  // of the returning ones (else the robot stood still, and every beam looks like its body).
  double max_steady_scene_share = 0.3;
  int max_scans = 2000;  // Spread evenly over the log, enough to judge.
};

struct SelfReturns {
  std::vector<int> beams;  // Beam indices, each with its neighbours (edges mix body and scene).
  double min_range_m = 0.0, max_range_m = 0.0;  // Of the beams' median ranges.
  // Runs of neighbouring beams, as their first and last beams' angles (rad).
  std::vector<std::pair<double, double>> sectors_rad;
  // "47 beams (130° to 141°, ...) return from 0.15–0.25 m in scan after scan of 601, ..."
  std::string Describe(int scans) const;
};

// None unless every scan has the same beams (count, first angle, step).
SelfReturns FindSelfReturns(const std::vector<LaserScan>& scans,
                            const SelfReturnOptions& options = {});

// The beams' ranges become no return in every scan.
void MaskBeams(const std::vector<int>& beams, std::vector<LaserScan>* scans);

}  // namespace calib

#endif  // CALIB_CORE_SCAN_SELF_RETURNS_H_
