#ifndef CALIB_SOLVERS_SCAN_MATCHING_CORRESPONDENCES_H_
#define CALIB_SOLVERS_SCAN_MATCHING_CORRESPONDENCES_H_

#include <calib/solvers/scan_matching/scan_points.h>

#include <Eigen/Core>
#include <vector>

// Point-to-segment correspondences for PL-ICP: each current point (already expressed in the
// reference frame) is paired with its nearest reference point and, on the side of the nearer of
// its two beam neighbours, the first point at least min_segment_length_m away: the segment whose
// line the point should lie on.
namespace calib {

struct Correspondence {
  int current = -1;      // Index into the current scan's points.
  int reference_a = -1;  // The nearest reference point.
  int reference_b = -1;  // Its beam neighbour: the segment is (a, b).
};

struct CorrespondenceOptions {
  double max_distance_m = 0.5;        // Farther nearest points are no correspondence.
  double max_segment_length_m = 0.5;  // Longer segments span a depth jump.
  double min_segment_length_m = 0.1;  // Shorter ones go on along the beams (dense scans).
};

// Finds the nearest reference point by walking the reference's beams outward from the point's
// polar angle until the beam angle alone puts any further point beyond the best distance
// (a point at polar offset Δ from a beam is at least ρ·sin|Δ| from it). `out` is overwritten.
void FindCorrespondences(const ScanPoints& reference,
                         const std::vector<Eigen::Vector2d>& current_in_reference_m,
                         const CorrespondenceOptions& options, std::vector<Correspondence>* out);

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_MATCHING_CORRESPONDENCES_H_
