#ifndef CALIB_SOLVERS_SCAN_MATCHING_CORRESPONDENCES_H_
#define CALIB_SOLVERS_SCAN_MATCHING_CORRESPONDENCES_H_

#include <calib/solvers/scan_matching/scan_points.h>

#include <Eigen/Core>
#include <array>
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
  // The line to hold the point to: through the first points on either side of a whose beams'
  // arc at a's range reaches min_segment_length_m / 2, or (a, b) when a side has none (a depth
  // jump, the scan's end).
  // It leaves a out: a is the point nearest to the current point, so its range noise is biased
  // towards it (on dense scans markedly), and so would be the residual.
  int line_a = -1;
  int line_b = -1;
};

struct CorrespondenceOptions {
  double max_distance_m = 0.5;        // Farther nearest points are no correspondence.
  double max_segment_length_m = 0.5;  // Longer segments span a depth jump.
  double min_segment_length_m = 0.1;  // Shorter ones go on along the beams (dense scans).
  // A partial scan's first and last this many beams are no nearest point (see AtScanEnd).
  int scan_end_beams = 3;
  // A reference point whose segments on its two sides (min_segment_length_m each) turn by more
  // than this is at a corner and no nearest point (see AtCorner); π: none is. The scan-point
  // calibration drops its lines that turn so much (scan_pair_lines.cc, SpansCorner).
  double max_bend_rad = 0.6;
};

// The search against one reference scan, repeated (ICP iterations): the segments of every
// reference point are walked once, here. `reference` must outlive it.
class CorrespondenceSearch {
 public:
  CorrespondenceSearch(const ScanPoints& reference, const CorrespondenceOptions& options);
  // The correspondences of the current points i = 0, stride, 2·stride, …; `out` is overwritten.
  void Find(const std::vector<Eigen::Vector2d>& current_in_reference_m, int stride,
            std::vector<Correspondence>* out) const;

 private:
  int Nearest(const Eigen::Vector2d& p) const;
  bool AtScanEnd(int a) const;
  bool AtCorner(int a) const;
  void Walk(int a, int side);

  const ScanPoints& reference_;
  CorrespondenceOptions options_;
  std::vector<Eigen::Vector2d> computed_units_;  // When the reference has no beam_unit.
  const std::vector<Eigen::Vector2d>* units_ = nullptr;
  // Per reference point and side (0: beam − 1, 1: beam + 1): the adjacent beam's point when
  // within max_segment_length_m, the end of the segment walked from it, and the first point whose
  // beams' arc reaches min_segment_length_m / 2 (the line's end); −1 for none.
  std::vector<std::array<int, 2>> neighbour_, segment_end_, half_end_;
  std::vector<char> at_corner_;  // AtCorner of each reference point.
};

// Finds the nearest reference point by walking the reference's beams outward from the point's
// polar angle until the beam angle alone puts any further point beyond the best distance
// (a point at polar offset Δ from a beam is at least ρ·sin|Δ| from it). `out` is overwritten.
void FindCorrespondences(const ScanPoints& reference,
                         const std::vector<Eigen::Vector2d>& current_in_reference_m,
                         const CorrespondenceOptions& options, std::vector<Correspondence>* out);

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_MATCHING_CORRESPONDENCES_H_
