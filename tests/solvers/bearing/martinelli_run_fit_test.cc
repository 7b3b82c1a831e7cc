#include <calib/core/bearing/bearing_model.h>
#include <calib/core/bearing/bearing_simulator.h>
#include <calib/solvers/bearing/martinelli_run_fit.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace calib {
namespace {

void ExpectAngleNear(double a, double b, double tol) { EXPECT_NEAR(WrapAngle(a - b), 0.0, tol); }

// Distance of x from the nearest point of {y + j·step}.
double ModDistance(double x, double y, double step) {
  const double d = std::fmod(std::abs(x - y), step);
  return std::min(d, step - d);
}

TEST(MartinelliRunFitTest, AlgorithmOneFindsTheCentreOfSymmetry) {
  const BearingCircle truth{1.7, 0.9, -2.0, 0.6};
  const double period = 2 * M_PI / 1.7;
  std::vector<double> s, beta;
  for (int i = 0; i <= 2000; ++i) {
    s.push_back(period * i / 2000.0);
    beta.push_back(CircleBearing(truth, s.back()));
  }
  const StatusOr<NodeSearch> node = FindNodeAlgorithm1(s, beta, 1.7, 100);
  ASSERT_TRUE(node.ok()) << node.message();
  EXPECT_LT(ModDistance(node->node_m, truth.node_m, 0.5 * period), 1e-5 * period);
  EXPECT_LT(node->spread_rad, 1e-4);
  EXPECT_GT(node->pairs, 1900);
  // The sum is 2θC = π − 2L (mod 2π): eq. 35 without the paper's reduction mod π.
  ExpectAngleNear(node->symmetric_sum_rad, 2 * truth.center_bearing_rad, 1e-5);
}

// A run off a fixed ratio q is a typed result (circle = false with the reason), not an error, so
// that the closed form can skip it without reading the message.
TEST(MartinelliRunFitTest, NonCircularRunIsATypedResult) {
  BearingSimOptions o;
  BearingRunSpec wiggle;
  wiggle.duration_s = 60.0;
  wiggle.wheel_speeds = [](double t) { return WheelSpeeds{0.05 + 0.03 * std::sin(0.2 * t), 0.05}; };
  o.runs = {wiggle};
  const BearingLog log = SimulateBearingLog(o);
  const StatusOr<CircularRunSamples> samples =
      ExtractCircularRun(log.runs[0], log.meta.wheel_radius_m);
  ASSERT_TRUE(samples.ok()) << samples.message();
  EXPECT_FALSE(samples->circle);
  EXPECT_NE(samples->not_circle.find("is not a circle"), std::string::npos) << samples->not_circle;
  o.runs = MartinelliRuns();
  const BearingLog circles = SimulateBearingLog(o);
  std::vector<bool> keep(circles.runs[0].bearings.size(), true);
  keep[0] = keep[1] = false;
  const StatusOr<CircularRunSamples> kept =
      ExtractCircularRun(circles.runs[0], circles.meta.wheel_radius_m, {}, &keep);
  ASSERT_TRUE(kept.ok()) << kept.message();
  EXPECT_TRUE(kept->circle);
  EXPECT_EQ(kept->s_m.size(), keep.size() - 2);
}

}  // namespace
}  // namespace calib
