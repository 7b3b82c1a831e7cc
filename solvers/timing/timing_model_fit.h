#ifndef CALIB_SOLVERS_TIMING_TIMING_MODEL_FIT_H_
#define CALIB_SOLVERS_TIMING_TIMING_MODEL_FIT_H_

#include <calib/core/status.h>
#include <calib/solvers/timing/laser_timing_calibration.h>
#include <calib/solvers/timing/latent_time_problem.h>
#include <calib/solvers/timing/latent_time_statistics.h>

#include <Eigen/Core>
#include <vector>

// One timing model fitted to the streams: rounds of solve → re-estimate scan noise and jitter →
// re-bracket (and, for a free-running clock, re-assign the sample indices) until they settle.
namespace calib {

struct TimingModelFit {
  SensorClockModel model = SensorClockModel::kStamps;
  LatentTimeState state;
  LatentLinearization lin;
  LatentCovariance covariance;
  std::vector<Eigen::Vector3d> errors;
  std::vector<double> sample_time_s;  // Latent times of every sample (relative).
  double kappa = 1.0;
  double score = 0.0;  // −2 log evidence (Laplace) + 2·(number of timing globals).
  int iterations = 0;
  int rounds = 0;
  bool converged = true;
};

StatusOr<TimingModelFit> FitTimingModel(const StreamSamples& data, SensorClockModel model,
                                        const LatentTimeState& initial,
                                        const LaserTimingOptions& options);

// The clock model's starting point from a fit of the stamp model: whole periods per interval
// (from the stamps where they sit on the period's grid and the motion agrees, else from the ratio
// of measured to wheel motion), the clock fitted to the stamps, indices re-assigned from them, and
// for stamps on the grid a stamp prior (τ, σ_s) from their scatter about the clock.
LatentTimeState ClockStartFromTimes(const StreamSamples& data, const TimingModelFit& stamps);

}  // namespace calib

#endif  // CALIB_SOLVERS_TIMING_TIMING_MODEL_FIT_H_
