#include <calib/core/random.h>
#include <calib/core/timing/wheel_angle_spline.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace calib {
namespace {

// Polls ~250 ms apart with ±40 ms of unevenness; both wheels accelerate constantly.
std::vector<EncoderSample> AcceleratingPolls(double left_speed, double left_acceleration,
                                             double right_speed, double right_acceleration) {
  Random random(3);
  std::vector<EncoderSample> polls;
  for (int k = 0; k < 40; ++k) {
    const double t = 0.25 * k + (k > 0 ? 0.04 * (2.0 * random.Uniform() - 1.0) : 0.0);
    polls.push_back(EncoderSample{t, left_speed * t + 0.5 * left_acceleration * t * t,
                                  right_speed * t + 0.5 * right_acceleration * t * t});
  }
  return polls;
}

// A constant acceleration is a parabola in the angle: the rates are exact (at the ends too) and
// the cubic between polls is the parabola, where a line misses α''·h²/8.
TEST(WheelAngleSpline, ReproducesAConstantAcceleration) {
  const std::vector<EncoderSample> polls = AcceleratingPolls(2.0, 1.5, -1.0, -0.8);
  for (size_t j = 0; j < polls.size(); ++j) {
    const WheelRates rates = WheelRatesAt(polls, j);
    EXPECT_NEAR(rates.left, 2.0 + 1.5 * polls[j].t_s, 1e-12) << j;
    EXPECT_NEAR(rates.right, -1.0 - 0.8 * polls[j].t_s, 1e-12) << j;
  }
  double worst_line = 0.0;
  for (size_t j = 0; j + 1 < polls.size(); ++j) {
    for (double f : {0.1, 0.5, 0.83}) {
      const double t = polls[j].t_s + f * (polls[j + 1].t_s - polls[j].t_s);
      double left = 0.0, right = 0.0, line_left = 0.0, line_right = 0.0;
      WheelAnglesInSegment(polls, j, t, true, &left, &right);
      WheelAnglesInSegment(polls, j, t, false, &line_left, &line_right);
      EXPECT_NEAR(left, 2.0 * t + 0.75 * t * t, 1e-12);
      EXPECT_NEAR(right, -1.0 * t - 0.4 * t * t, 1e-12);
      worst_line = std::max(worst_line, std::abs(line_left - (2.0 * t + 0.75 * t * t)));
    }
  }
  EXPECT_GT(worst_line, 1e-3);  // 1.5 rad/s² · (0.25 s)² / 8 ≈ 0.012 rad at mid-poll.
}

// A wheel that stops and reverses: the rate is 0 at the turning poll and the curve never turns
// back between polls; a jump in speed does not overshoot either.
TEST(WheelAngleSpline, StaysMonotoneBetweenPolls) {
  std::vector<EncoderSample> polls;
  const double angles[] = {0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 2.5, 2.0};
  for (int k = 0; k < 8; ++k) polls.push_back(EncoderSample{0.25 * k, angles[k], -angles[k]});
  EXPECT_EQ(WheelRatesAt(polls, 5).left, 0.0);  // 3.0 is the turning point.
  EXPECT_EQ(WheelRatesAt(polls, 2).left, 0.0);  // Starts from rest.
  for (size_t j = 0; j + 1 < polls.size(); ++j) {
    const double low = std::min(polls[j].left_rad, polls[j + 1].left_rad);
    const double high = std::max(polls[j].left_rad, polls[j + 1].left_rad);
    double previous = polls[j].left_rad;
    for (int i = 1; i <= 50; ++i) {
      const double t = polls[j].t_s + 0.25 * i / 50.0;
      double left = 0.0, right = 0.0;
      WheelAnglesInSegment(polls, j, t, true, &left, &right);
      EXPECT_GE(left, low - 1e-12);
      EXPECT_LE(left, high + 1e-12);
      EXPECT_GE((left - previous) * (polls[j + 1].left_rad - polls[j].left_rad), -1e-15);
      EXPECT_NEAR(right, -left, 1e-12);
      previous = left;
    }
  }
}

// Next to a gap (a step over four times the other), the rate comes from the side without it.
TEST(WheelAngleSpline, RatesIgnoreASecantAcrossAGap) {
  std::vector<EncoderSample> polls;
  for (double t : {0.0, 0.25, 0.5, 0.75, 3.0, 3.25, 3.5}) {
    polls.push_back(EncoderSample{t, 2.0 * t + 0.5 * t * t, 0.0});
  }
  for (size_t j = 4; j < polls.size(); ++j) polls[j].left_rad += 5.0;  // Drove on, unlogged.
  EXPECT_NEAR(WheelRatesAt(polls, 3).left, 2.0 + 0.75, 1e-12);
  EXPECT_NEAR(WheelRatesAt(polls, 4).left, 2.0 + 3.0, 1e-12);
}

// The hand-written partials of the cubic against central differences, inside the segment and
// on the tangents beyond it.
TEST(WheelAngleSpline, PartialsMatchNumericDifferences) {
  const double e0 = 1.0, e1 = 1.26, a0 = 0.4, a1 = 1.1, m0 = 2.1, m1 = 3.4;
  for (double t : {0.9, 1.0 + 1e-7, 1.05, 1.13, 1.25, 1.3}) {
    const HermitePartials p = HermiteWheelAnglePartials(t, e0, e1, a0, a1, m0, m1);
    const double h = 1e-7;
    const auto f = [&](double tt, double ee0, double ee1) {
      return HermiteWheelAngle(tt, ee0, ee1, a0, a1, m0, m1);
    };
    EXPECT_NEAR(p.t, (f(t + h, e0, e1) - f(t - h, e0, e1)) / (2 * h), 1e-6) << t;
    EXPECT_NEAR(p.e0, (f(t, e0 + h, e1) - f(t, e0 - h, e1)) / (2 * h), 1e-6) << t;
    EXPECT_NEAR(p.e1, (f(t, e0, e1 + h) - f(t, e0, e1 - h)) / (2 * h), 1e-6) << t;
  }
  // Equal rates on the secant: the line.
  const double secant = (a1 - a0) / (e1 - e0);
  EXPECT_NEAR(HermiteWheelAngle(1.1, e0, e1, a0, a1, secant, secant), a0 + (1.1 - e0) * secant,
              1e-14);
}

}  // namespace
}  // namespace calib
