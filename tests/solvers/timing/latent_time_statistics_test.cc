#include <calib/solvers/timing/latent_time_statistics.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <random>

namespace calib {
namespace {

// A linearisation with the shape of a real one: three positive semi-definite band blocks (one per
// scan component), sensor and encoder latents interleaved, latents off their prior means.
LatentLinearization RandomLinearization(int n, int w, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  LatentLinearization lin;
  lin.num_intervals = n;
  lin.noise_sigma = Eigen::Vector3d(0.5e-3, 0.6e-3, 1.2e-3);
  lin.latent_value.resize(n);
  for (int i = 0; i < n; ++i) {
    lin.latent_is_sensor.push_back(i % 3 != 2);
    lin.latent_owner.push_back(i);
    lin.latent_value(i) = 0.01 * normal(rng);
  }
  for (int c = 0; c < 3; ++c) {
    // H_c = Σ_rows j jᵀ with each row spanning w + 1 neighbouring latents: banded and PSD.
    lin.h_ll_band_c[c] = Eigen::MatrixXd::Zero(w + 1, n);
    lin.b_l_c[c] = Eigen::VectorXd::Zero(n);
    for (int row = 0; row + w < n; ++row) {
      Eigen::VectorXd j(w + 1);
      for (int a = 0; a <= w; ++a) j(a) = 30.0 * normal(rng);
      const double r = normal(rng);
      for (int a = 0; a <= w; ++a) {
        lin.b_l_c[c](row + a) += j(a) * r;
        for (int b = a; b <= w; ++b) lin.h_ll_band_c[c](b - a, row + a) += j(a) * j(b);
      }
      lin.rr_c(c) += r * r;
    }
  }
  return lin;
}

Eigen::Matrix<double, 5, 1> Logs(const NoiseScales& s) {
  Eigen::Matrix<double, 5, 1> theta;
  theta << s.scan.array().log(), std::log(s.sensor_s), std::log(s.encoder_s);
  return theta;
}

NoiseScales FromLogs(const Eigen::Matrix<double, 5, 1>& theta) {
  NoiseScales s;
  s.scan = theta.head<3>().array().exp();
  s.sensor_s = std::exp(theta(3));
  s.encoder_s = std::exp(theta(4));
  return s;
}

TEST(LatentEvidence, GradientMatchesCentralDifferences) {
  const LatentLinearization lin = RandomLinearization(60, 3, 7);
  NoiseScales scales;
  scales.scan = Eigen::Vector3d(0.7e-3, 0.4e-3, 1.5e-3);
  scales.sensor_s = 0.012;
  scales.encoder_s = 0.02;
  const double offset_s = 0.004;
  const StatusOr<LatentEvidence> e = LatentEvidenceWithGradient(lin, offset_s, scales, true);
  ASSERT_TRUE(e.ok()) << e.message();
  const StatusOr<double> value = LatentNegLogEvidence(lin, offset_s, scales);
  ASSERT_TRUE(value.ok());
  EXPECT_DOUBLE_EQ(e->value, *value);
  const Eigen::Matrix<double, 5, 1> theta = Logs(scales);
  constexpr double kStep = 1e-5;
  for (int i = 0; i < 5; ++i) {
    Eigen::Matrix<double, 5, 1> up = theta, down = theta;
    up(i) += kStep;
    down(i) -= kStep;
    const double numeric = (*LatentNegLogEvidence(lin, offset_s, FromLogs(up)) -
                            *LatentNegLogEvidence(lin, offset_s, FromLogs(down))) /
                           (2.0 * kStep);
    EXPECT_NEAR(e->gradient(i), numeric, 1e-5 * std::max(1.0, std::abs(numeric))) << i;
  }
}

TEST(LatentEvidence, MaximisationEndsAtAStationaryPointInsideTheBounds) {
  const LatentLinearization lin = RandomLinearization(300, 2, 11);
  NoiseScales start;
  start.scan = lin.noise_sigma;
  start.sensor_s = 0.05;
  start.encoder_s = 0.001;
  NoiseScaleFit fit;
  fit.floor_s = 1e-4;
  fit.ceiling_s = 1.0;
  const NoiseScales best = MaximizeLatentEvidence(lin, 0.0, start, fit);
  const StatusOr<LatentEvidence> at_best = LatentEvidenceWithGradient(lin, 0.0, best, true);
  const StatusOr<LatentEvidence> at_start = LatentEvidenceWithGradient(lin, 0.0, start, true);
  ASSERT_TRUE(at_best.ok() && at_start.ok());
  EXPECT_LT(at_best->value, at_start->value);
  const Eigen::Matrix<double, 5, 1> theta = Logs(best);
  for (int i = 0; i < 5; ++i) {
    const bool at_floor = i >= 3 && theta(i) <= std::log(fit.floor_s) + 1e-6;
    if (at_floor) {
      EXPECT_GT(at_best->gradient(i), 0.0) << i;  // Held at the floor only if pushing out.
    } else {
      EXPECT_LT(std::abs(at_best->gradient(i)), 0.05) << i;
    }
  }
  // Fixed scales stay as they were.
  NoiseScaleFit only_jitter = fit;
  only_jitter.scan = false;
  EXPECT_EQ(MaximizeLatentEvidence(lin, 0.0, start, only_jitter).scan, start.scan);
}

}  // namespace
}  // namespace calib
