#ifndef CALIB_SOLVERS_SCAN_CALIBRATION_SCAN_PAIR_LINES_H_
#define CALIB_SOLVERS_SCAN_CALIBRATION_SCAN_PAIR_LINES_H_

#include <calib/problems/scan/scan_pair_residual.h>
#include <calib/solvers/scan_calibration/scan_pair_timeline.h>
#include <calib/solvers/scan_calibration/scan_point_calibration.h>

#include <vector>

// One pair of the scan-point calibration: its wheels, and the point-to-line correspondences
// found at the current parameters.
namespace calib {

struct ScanPair {
  int reference = 0, current = 0;  // Indices into ScanPointInput::scans; reference first in time.
  int cluster = 0;
  PairTimeline timeline;
  ScanPairGeometry geometry;
  // Per line: Var(distance)/σ² for independent range noise on its three points, and the
  // distance itself at the parameters the lines were found at.
  std::vector<double> variance_factor;
  std::vector<double> distance_m;
};

// Finds the current scan's correspondences in the reference (both placed through `c` with the
// beams' times shifted by time_offset_s), at most max_lines_per_pair of them, each with weight
// 1. Fails only on a malformed scan.
Status FindPairLines(const ScanPointInput& input, const LaserCalibration& c, double time_offset_s,
                     const ScanPointOptions& options, ScanPair* pair);

// Drops the lines beyond gate_sigmas and weights the rest: w = √ρ'(z²)/(σ√v), z = d/(σ√v), ρ
// Cauchy at loss_scale_sigmas (iteratively reweighted least squares). Returns the lines kept.
int WeighPairLines(double range_sigma_m, const ScanPointOptions& options, ScanPair* pair);

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_CALIBRATION_SCAN_PAIR_LINES_H_
