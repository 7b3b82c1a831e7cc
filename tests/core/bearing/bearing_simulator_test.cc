#include <calib/core/bearing/bearing_log_io.h>
#include <calib/core/bearing/bearing_model.h>
#include <calib/core/bearing/bearing_simulator.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace calib {
namespace {

TEST(BearingSimulatorTest, Section81Setting) {
  BearingSimOptions o;
  o.encoder_noise_k = 0.0;
  o.initial_distance_run = 2;
  BearingSimTruth truth;
  const BearingLog log = SimulateBearingLog(o, &truth);
  ASSERT_TRUE(ValidateBearingLog(log).ok()) << ValidateBearingLog(log).message();
  ASSERT_EQ(log.runs.size(), 3u);
  ASSERT_TRUE(log.meta.initial_distance.has_value());
  EXPECT_EQ(log.meta.initial_distance->run, 2);
  EXPECT_NEAR(log.meta.initial_distance->meters, 1.0, 1e-12);
  const double qs[3] = {0.9, 0.0, -1.0};
  for (int i = 0; i < 3; ++i) {
    const BearingRun& run = log.runs[i];
    const BearingRunTruth& t = truth.runs[i];
    EXPECT_EQ(run.id, i + 1);
    // One loop at ν = 0.05 m/s: 2π/|ξq| of right-wheel travel; encoders at 50 Hz, bearings 1 Hz.
    const double duration = run.odometry.back().t_s - run.odometry.front().t_s;
    EXPECT_NEAR(duration * 0.05 * std::abs(t.xi_q_per_m), 2 * M_PI, 1e-9);
    EXPECT_NEAR((run.odometry.size() - 1) / duration, 50.0, 50.0 / duration + 1e-9);
    EXPECT_EQ(run.bearings.size(), static_cast<size_t>(std::floor(duration)) + 1);
    const double right = run.odometry.back().right_rad - run.odometry.front().right_rad;
    const double left = run.odometry.back().left_rad - run.odometry.front().left_rad;
    EXPECT_NEAR(left / right, qs[i], 1e-12);
    // Noise-free bearings equal the model at the true poses.
    for (size_t j = 0; j < run.bearings.size(); ++j) {
      EXPECT_NEAR(run.bearings[j].bearing_rad,
                  BearingFromPose(t.world_T_robot_at_bearings[j], o.truth.phi_rad, o.truth.rho_m,
                                  o.truth.psi_rad),
                  1e-12);
    }
  }
}

TEST(BearingSimulatorTest, NoiseHasTheRequestedStatistics) {
  BearingSimOptions o;
  o.bearing_noise_rad = 0.02;
  o.encoder_noise_k = 0.01;
  BearingRunSpec spec;
  spec.q = 0.5;
  spec.loops = 5.0;
  o.runs = {spec};
  BearingSimOptions clean = o;
  clean.bearing_noise_rad = 0.0;
  clean.encoder_noise_k = 0.0;
  const BearingLog noisy_log = SimulateBearingLog(o);
  const BearingLog clean_log = SimulateBearingLog(clean);
  const BearingRun& noisy = noisy_log.runs[0];
  const BearingRun& exact = clean_log.runs[0];
  double sum2 = 0.0;
  for (size_t j = 0; j < noisy.bearings.size(); ++j) {
    const double e = WrapAngle(noisy.bearings[j].bearing_rad - exact.bearings[j].bearing_rad);
    sum2 += e * e;
  }
  EXPECT_NEAR(std::sqrt(sum2 / noisy.bearings.size()), 0.02, 0.002);
  // Increment noise: variance K²/r·|Δα| per wheel and sample.
  double z2_left = 0.0, z2_right = 0.0;
  const size_t n = noisy.odometry.size() - 1;
  for (size_t i = 1; i <= n; ++i) {
    const double true_l = exact.odometry[i].left_rad - exact.odometry[i - 1].left_rad;
    const double true_r = exact.odometry[i].right_rad - exact.odometry[i - 1].right_rad;
    const double el = noisy.odometry[i].left_rad - noisy.odometry[i - 1].left_rad - true_l;
    const double er = noisy.odometry[i].right_rad - noisy.odometry[i - 1].right_rad - true_r;
    z2_left += el * el / (1e-4 / 0.3 * std::abs(true_l)) / n;
    z2_right += er * er / (1e-4 / 0.3 * std::abs(true_r)) / n;
  }
  EXPECT_NEAR(z2_left, 1.0, 0.05);
  EXPECT_NEAR(z2_right, 1.0, 0.05);
}

}  // namespace
}  // namespace calib
