#include <calib/core/laser/laser_simulator.h>
#include <calib/core/timing/stream_samples.h>
#include <calib/solvers/timing/latent_time_problem.h>
#include <calib/solvers/timing/latent_time_statistics.h>
#include <gtest/gtest.h>

#include <cmath>

#include "tests/solvers/timing/perturbed_streams.h"

namespace calib {
namespace {

// The band-arrow solve and Ceres' own LM (sparse Cholesky) reach the same optimum of the same
// problem, for both sensor clock models.
struct LatentScene {
  StreamSamples data;
  LatentTimeState state;
};

// 400 sensor periods with scattered encoder stamps (and sensor stamps for the stamp model), the
// state at the truth.
LatentScene MakeScene(SensorClockModel model) {
  LaserSimOptions o;
  o.num_intervals = 400;
  o.mean_interval_s = 0.0995;
  o.interval_jitter_s = 0.0;
  o.max_wheel_speed = 3.0;
  o.scan_noise_sigma = Eigen::Vector3d(0.0005, 0.0005, 0.001);
  o.seed = 5;
  LaserSimTruth truth;
  LaserStreams streams = SimulateLaserStreams(o, 50.0, &truth);
  test::ScatterEncoderStamps(&streams, 0.004, 11);
  if (model == SensorClockModel::kStamps) test::ScatterSensorStamps(&streams, 0.005, 0.01, 12);
  const StatusOr<StreamSamples> data =
      BuildStreamSamples(streams.odometry, streams.sensor_poses, "test");
  EXPECT_TRUE(data.ok()) << data.message();
  LatentScene scene{data.ok() ? *data : StreamSamples{}, {}};
  LatentTimeState& state = scene.state;
  state.calibration.odometry = truth.odometry;
  state.calibration.base_T_sensor = truth.base_T_sensor;
  state.noise_sigma = o.scan_noise_sigma;
  state.sensor_sigma_s = 0.005;
  state.encoder_sigma_s = 0.004;
  if (model == SensorClockModel::kFreeRunning) {
    state.clock_index.clear();
    std::vector<double> stamps;
    for (size_t k = 0; k < data->samples.size(); ++k) {
      state.clock_index.push_back(static_cast<double>(k));
      stamps.push_back(data->samples[k].stamp_s);
    }
    state.clock = FitSampleClock(state.clock_index, stamps);
    state.sensor_sigma_s = 1e-4;
  }
  return scene;
}

LaserRefinementOptions TwoThreads() {
  LaserRefinementOptions options;
  options.num_threads = 2;
  return options;
}

void ExpectSameOptimum(SensorClockModel model) {
  const LatentScene scene = MakeScene(model);
  const StreamSamples* data = &scene.data;
  ASSERT_FALSE(data->samples.empty());
  LatentTimeProblem band(*data, model, scene.state, TwoThreads(), true);
  LatentTimeProblem reference(*data, model, scene.state, TwoThreads(), true);
  BandArrowSummary band_summary;
  ceres::Solver::Summary ceres_summary;
  ASSERT_TRUE(band.Solve(&band_summary, 1e-6).ok());
  ASSERT_TRUE(reference.SolveWithCeres(&ceres_summary, 1e-6).ok());
  EXPECT_TRUE(band_summary.converged);
  EXPECT_NEAR(band_summary.final_cost, ceres_summary.final_cost, 1e-4);
  const LatentTimeState a = band.state(), b = reference.state();
  // σ of the six parameters on such a log: ~1e-5 m for the lengths, ~1e-3 rad for the angle.
  const LaserParamVector difference = a.calibration.ToVector() - b.calibration.ToVector();
  EXPECT_LT(difference.head<5>().cwiseAbs().maxCoeff(), 5e-7) << difference.transpose();
  EXPECT_LT(std::abs(difference(5)), 2e-4);
  for (size_t k = 0; k < data->samples.size(); ++k) {
    EXPECT_NEAR(band.SampleTime(static_cast<int>(k)), reference.SampleTime(static_cast<int>(k)),
                2e-4);
  }
}

TEST(LatentTimeProblemTest, BandArrowSolveMatchesCeresStampModel) {
  ExpectSameOptimum(SensorClockModel::kStamps);
}

TEST(LatentTimeProblemTest, BandArrowSolveMatchesCeresClockModel) {
  ExpectSameOptimum(SensorClockModel::kFreeRunning);
}

// The rounds keep one problem and set each round's σ's in place: solved again, it reaches the
// optimum (and the linearisation) of a problem built with those σ's.
TEST(LatentTimeProblemTest, NoiseScalesSetInPlaceMatchARebuiltProblem) {
  const LatentScene scene = MakeScene(SensorClockModel::kStamps);
  ASSERT_FALSE(scene.data.samples.empty());
  LatentTimeProblem reused(scene.data, SensorClockModel::kStamps, scene.state, TwoThreads(), true);
  BandArrowSummary summary;
  ASSERT_TRUE(reused.Solve(&summary, 1e-6).ok());
  LatentTimeState rescaled = reused.state();
  rescaled.noise_sigma *= 1.5;
  rescaled.sensor_sigma_s *= 0.5;
  rescaled.encoder_sigma_s *= 2.0;
  ASSERT_TRUE(
      reused.SetNoiseScales(rescaled.noise_sigma, rescaled.sensor_sigma_s, rescaled.encoder_sigma_s)
          .ok());
  LatentTimeProblem rebuilt(scene.data, SensorClockModel::kStamps, rescaled, TwoThreads(), true);
  ASSERT_TRUE(reused.Solve(&summary, 1e-6).ok());
  ASSERT_TRUE(rebuilt.Solve(&summary, 1e-6).ok());
  const LaserParamVector difference =
      reused.state().calibration.ToVector() - rebuilt.state().calibration.ToVector();
  EXPECT_LT(difference.cwiseAbs().maxCoeff(), 1e-9) << difference.transpose();
  const StatusOr<LatentLinearization> a = reused.Linearize(), b = rebuilt.Linearize();
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_LT((a->h_gg - b->h_gg).cwiseAbs().maxCoeff(), 1e-6 * b->h_gg.cwiseAbs().maxCoeff());
  EXPECT_LT((a->h_ll_band - b->h_ll_band).cwiseAbs().maxCoeff(),
            1e-6 * b->h_ll_band.cwiseAbs().maxCoeff());
  EXPECT_NEAR(a->data_cost, b->data_cost, 1e-6 * b->data_cost);
  // A jitter cannot go from positive to 0 in place: the latents would have to go.
  EXPECT_FALSE(reused.SetNoiseScales(rescaled.noise_sigma, 0.0, rescaled.encoder_sigma_s).ok());
}

// The intervals' profile scores (latents optimised out, their priors included) sum to the
// globals' gradient at the optimum, 0, for both clock models: without the priors' share or the
// latents' gain they would not.
TEST(LatentTimeProblemTest, ProfileScoresSumToZeroAtTheOptimum) {
  for (const SensorClockModel model : {SensorClockModel::kStamps, SensorClockModel::kFreeRunning}) {
    const LatentScene scene = MakeScene(model);
    ASSERT_FALSE(scene.data.samples.empty());
    LatentTimeProblem problem(scene.data, model, scene.state, TwoThreads(), true);
    BandArrowSummary summary;
    ASSERT_TRUE(problem.Solve(&summary, 1e-9).ok());
    const StatusOr<LatentLinearization> lin = problem.Linearize(true);
    ASSERT_TRUE(lin.ok()) << lin.message();
    const LatentTimeState state = problem.state();
    const LatentPrior prior =
        MakeLatentPrior(*lin, state.offset_s, state.sensor_sigma_s, state.encoder_sigma_s);
    const StatusOr<LatentCovariance> covariance = MarginalLatentCovariance(*lin, prior);
    ASSERT_TRUE(covariance.ok()) << covariance.message();
    const StatusOr<Eigen::MatrixXd> u = LatentProfileScores(*lin, prior, *covariance);
    ASSERT_TRUE(u.ok()) << u.message();
    ASSERT_EQ(u->rows(), static_cast<Eigen::Index>(problem.num_intervals()));
    // The clock's curvature has a prior the scores leave out (it is no observation).
    const Eigen::Index checked = model == SensorClockModel::kFreeRunning ? 8 : u->cols();
    for (Eigen::Index g = 0; g < checked; ++g) {
      EXPECT_LT(std::abs(u->col(g).sum()), 1e-3 * u->col(g).norm()) << g;
    }
    // Each interval's score is no longer 0: the meat of the sandwich.
    EXPECT_GT(u->col(0).norm(), 0.0);
  }
}

}  // namespace
}  // namespace calib
