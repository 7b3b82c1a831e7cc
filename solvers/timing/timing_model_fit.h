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

// The clock model's starting point from a fit of the stamp model: the clock by the phase of the
// latent times the data pinned (FitClockByPhase), then indices re-assigned from the stamps.
LatentTimeState ClockStartFromTimes(const StreamSamples& data, const TimingModelFit& stamps);

}  // namespace calib

#endif  // CALIB_SOLVERS_TIMING_TIMING_MODEL_FIT_H_
