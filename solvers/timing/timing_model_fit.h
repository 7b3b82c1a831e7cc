#ifndef CALIB_SOLVERS_TIMING_TIMING_MODEL_FIT_H_
#define CALIB_SOLVERS_TIMING_TIMING_MODEL_FIT_H_

#include <calib/core/status.h>
#include <calib/solvers/timing/laser_timing_calibration.h>
#include <calib/solvers/timing/latent_error_covariance.h>
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
  // The globals' covariance as reported: κ·covariance.globals, and once polished also at least
  // the sandwich's in every direction (DominatingCovariance; the largest ratio between them), or
  // with the lag-1 term where the scan poses err independently (`neighbours`), plus what the
  // cubic's wheel angles between polls add (LatentAngleCovariance).
  Eigen::MatrixXd globals_covariance;
  double sandwich_ratio = 1.0;
  NeighbourCorrelation neighbours;  // Of the intervals' errors, once polished.
  double score = 0.0;               // −2 log evidence (Laplace) + 2·(number of timing globals).
  int iterations = 0;
  int rounds = 0;
  bool converged = true;
  bool polished = false;        // PolishTimingModel ran: the fit is at its optimum,
  bool has_statistics = false;  // and κ and the statistics are final.
};

// Rounds at the looser tolerance (kLatentRoundCostTolerance) until the σ's settle; the models
// are compared there, and the one kept is then polished.
StatusOr<TimingModelFit> FitTimingModel(const StreamSamples& data, SensorClockModel model,
                                        const LatentTimeState& initial,
                                        const LaserTimingOptions& options);
// The fit re-solved to the full tolerance (kLatentCostTolerance) at its latest σ's, with its
// statistics and the robust loss's covariance correction κ; without them (`with_statistics`
// false: κ = 1 and the model's covariance) for a fit that the redescending passes replace, where
// they took a tenth of the calibration.
Status PolishTimingModel(const StreamSamples& data, const LaserTimingOptions& options,
                         TimingModelFit* fit, bool with_statistics = true);

// A jitter σ to start the rounds from: twice the stamps' robust scatter about their regular grid
// (a pick-up stamp lags its sample by more than the stamps scatter), within [the floor of the
// search, a quarter period]. Stamps that are the sample times start at the floor, where the
// latent times barely move; starting high instead lets the latents absorb the scan noise in the
// first round and the rounds then take long to shed it.
double StartingJitter(const std::vector<double>& stamps_s, double period_s);

}  // namespace calib

#endif  // CALIB_SOLVERS_TIMING_TIMING_MODEL_FIT_H_
