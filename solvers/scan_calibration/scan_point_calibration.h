#ifndef CALIB_SOLVERS_SCAN_CALIBRATION_SCAN_POINT_CALIBRATION_H_
#define CALIB_SOLVERS_SCAN_CALIBRATION_SCAN_POINT_CALIBRATION_H_

#include <calib/core/encoder_sample.h>
#include <calib/core/laser/laser_params.h>
#include <calib/core/scan/laser_scan.h>
#include <calib/core/status.h>
#include <calib/solvers/scan_matching/correspondences.h>

#include <string>
#include <vector>

// The calibration refined against the scan points themselves (no scan matcher in between): pairs
// of scans a few decimetres apart, every beam placed at its own time through the wheels, the
// calibrated odometry and the mounting (so the sweep is de-skewed by the very parameters being
// estimated), and point-to-line residuals between the two scans of each pair, all in one Ceres
// problem. The correspondences and robust weights are found again between solves (an ICP over
// the six parameters), until the estimate stops moving.
namespace calib {

struct ScanPointInput {
  // The distinct samples in time order (a repeated sample must appear once), in a frame that
  // turns counter-clockwise with the base (mirror an upside-down sensor's scans first).
  std::vector<const LaserScan*> scans;
  // Per scan: the time of its first beam on the encoders' clock (its stamp corrected by the
  // timing calibration); the beams follow every time_increment_s.
  std::vector<double> first_beam_time_s;
  const std::vector<EncoderSample>* encoders = nullptr;  // Sorted by time.
  std::string source;                                    // For messages.
};

struct ScanPointOptions {
  // A current point's line: the reference return along its polar angle and the first return
  // min_segment_length_m on along the beams (max_distance_m and max_segment_length_m as named).
  // Segments of 0.25 m, not the matcher's 0.1: at 1 cm of range noise the direction of a short
  // segment is mostly noise, and its second-order error put the mounting ~1σ off (600 scans).
  CorrespondenceOptions correspondence = {0.5, 0.5, 0.25};
  // A pair is a scan and the first later one this far from it (through the odometry), within
  // max_pair_span_s; pairs whose motion stays below the minima carry nothing and are skipped.
  double pair_distance_m = 0.3;
  double pair_angle_rad = 0.3;
  double max_pair_span_s = 2.0;
  double min_pair_distance_m = 0.05;
  double min_pair_angle_rad = 0.05;
  int max_pairs = 1500;            // Spread evenly over the log when more are possible.
  int max_lines_per_pair = 300;    // Correspondences kept per pair (every k-th).
  int min_lines_per_pair = 30;     // Fewer: the pair has too little overlap and is left out.
  double loss_scale_sigmas = 3.0;  // Cauchy weights on the whitened distances.
  double gate_sigmas = 8.0;        // Farther correspondences are dropped.
  // The beams' times shifted by a constant δ estimated with the calibration (what the given
  // times still miss: a driver's stamp convention, a timing calibration's residual bias).
  bool estimate_time_offset = true;
  // The wheels' timeline reaches this far beyond each pair's beams, for δ to move in.
  double max_time_offset_s = 0.2;
  int max_rounds = 10;
  // First a few rounds on consecutive scans (short motion: robust to a start far off).
  bool warm_start = true;
  double tolerance_sigmas = 0.05;  // Stop when no parameter moves more than this in a round.
  // Clusters of consecutive pairs whose errors may be correlated (scans shared between pairs):
  // four times the pairs' mean span in scans, but at least 15 clusters.
  int min_clusters = 15;
  int num_threads = 2;
};

struct ScanPointCalibration {
  LaserCalibration estimate;
  // The cluster sandwich H⁻¹BH⁻¹ over blocks of consecutive pairs (points of one scan, a wall's
  // shape, share errors), never smaller than the independent-noise model σ̂²H⁻¹.
  LaserParamMatrix covariance = LaserParamMatrix::Zero();
  LaserParamVector stddev = LaserParamVector::Zero();
  double time_offset_s = 0.0;  // δ: the true time of a beam is its given time + δ.
  double time_offset_stddev_s = 0.0;
  // How much larger than the independent-noise model some combination varies (≥ 1).
  double correlation_inflation = 1.0;
  int pairs = 0, lines = 0, rounds = 0, clusters = 0;
  double range_sigma_m = 0.0;  // σ̂ of the point-to-line distances (robust).
  double inlier_fraction = 0.0;
  bool converged = false;
  double seconds = 0.0;
  std::vector<std::string> warnings;
};

// Refines `initial` (e.g. the two-stage calibration). Fails on malformed input, when the scans
// give fewer than a dozen usable pairs, or when the pairs do not determine the six parameters.
StatusOr<ScanPointCalibration> CalibrateOnScanPoints(const ScanPointInput& input,
                                                     const LaserCalibration& initial,
                                                     const ScanPointOptions& options = {});

}  // namespace calib

#endif  // CALIB_SOLVERS_SCAN_CALIBRATION_SCAN_POINT_CALIBRATION_H_
