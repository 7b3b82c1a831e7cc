#ifndef CALIB_SOLVERS_BEARING_BEARING_CONSISTENCY_H_
#define CALIB_SOLVERS_BEARING_BEARING_CONSISTENCY_H_

#include <calib/core/bearing/bearing_log.h>

#include <vector>

// What the bearings say about their own noise before any model of the robot: the agreement of
// each bearing with its neighbours in time, and robust scales.
namespace calib {

// How each bearing agrees with its neighbours in time: a quadratic in t fitted to up to
// `half_window` bearings on each side (unwrapped around their circular mean, trimmed at 3 MADs),
// its prediction error z normalized to unit variance for white noise; σ = 1.4826·median|z|
// estimates σβ without any model of the robot (plus the quadratic's own misfit, so from above).
struct BearingConsistency {
  std::vector<std::vector<double>> z;
  std::vector<double> run_sigma_rad;  // The same per run (a quadratic fits some runs worse).
  double sigma_rad = 0.0;
};

BearingConsistency CheckConsistency(const BearingLog& log, int half_window = 4);

// 1.4826·median|e| over every error (0 without errors).
double RobustSigma(const std::vector<std::vector<double>>& errors);

// E[z² | |z| < c] for a standard normal z: the variance kept by an inlier cut at c·σ.
double TruncatedVariance(double c);

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_BEARING_CONSISTENCY_H_
