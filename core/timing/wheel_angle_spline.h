#ifndef CALIB_CORE_TIMING_WHEEL_ANGLE_SPLINE_H_
#define CALIB_CORE_TIMING_WHEEL_ANGLE_SPLINE_H_

#include <calib/core/encoder_sample.h>

#include <algorithm>
#include <cmath>
#include <vector>

// The cumulative wheel angles between encoder polls as a monotone cubic Hermite curve. A line
// between polls ~250 ms apart misses −α''·(t − e_j)(e_{j+1} − t)/2 while the robot accelerates:
// at a few rad/s² that is a millimetre of travel, as large as a scan match's noise, and it
// follows the acceleration, so a time offset fitted through it is biased and too confident.
namespace calib {

// Wheel rates (rad/s) at an encoder sample: the slope of the parabola through the sample and its
// neighbours (exact for a constant acceleration, on uneven polls too), zero where the wheel
// reverses or stops, and at most three times the neighbouring secants (Fritsch and Carlson 1980:
// the curve then never turns back between polls). At the ends, and next to a step over four times
// the other (a gap: a secant across it is an average, not a rate), the parabola through the
// sample and the next two on the other side.
struct WheelRates {
  double left = 0.0;
  double right = 0.0;
};

// The parabola's slope at the shared sample of two steps (durations h_near, h_far; secants
// d_near, d_far). Centred: the steps on either side; one-sided: the near step, then the far one.
inline double ParabolaRate(double h_near, double d_near, double h_far, double d_far, bool centred) {
  if (!(d_near * d_far > 0.0)) return 0.0;
  const double rate = centred ? (h_far * d_near + h_near * d_far) / (h_near + h_far)
                              : d_near + (d_near - d_far) * h_near / (h_near + h_far);
  if (!(rate * d_near > 0.0)) return 0.0;
  const double limit = 3.0 * std::min(std::abs(d_near), std::abs(d_far));
  return std::copysign(std::min(std::abs(rate), limit), rate);
}

// Which polls a rate's parabola goes through: the sample and its neighbours, or the sample and
// the next two (forward) or the two before (backward), where they exist. The one-sided curves
// honour every poll too; where the acceleration jumps between polls they disagree, by about 2.3
// times the centred curve's error (RMS, for a jump at a uniformly random place).
enum class RateSide { kCentred, kForward, kBackward };

// `time_s(i)` is sample i's time (its stamp, or its estimated true time).
template <typename TimeOf>
WheelRates WheelRatesAt(const std::vector<EncoderSample>& odometry, size_t j, TimeOf time_s,
                        RateSide side = RateSide::kCentred) {
  const size_t n = odometry.size();
  if (n < 2) return {};
  // Step i: from sample i to i + 1; valid for 0 <= i < n − 1.
  const auto step = [&](size_t i) { return time_s(i + 1) - time_s(i); };
  const auto secant = [&](size_t i, bool left) {
    const double a0 = left ? odometry[i].left_rad : odometry[i].right_rad;
    const double a1 = left ? odometry[i + 1].left_rad : odometry[i + 1].right_rad;
    return (a1 - a0) / step(i);
  };
  const auto rates = [&](size_t near, size_t far, bool centred) {
    const double h_near = step(near), h_far = step(far);
    return WheelRates{
        ParabolaRate(h_near, secant(near, true), h_far, secant(far, true), centred),
        ParabolaRate(h_near, secant(near, false), h_far, secant(far, false), centred)};
  };
  const auto one_sided = [&](size_t near, bool forward) {
    const bool has_far = forward ? near + 2 < n : near >= 1;
    const size_t far = forward ? near + 1 : near - 1;
    if (has_far && step(far) <= 4.0 * step(near)) return rates(near, far, false);
    return WheelRates{secant(near, true), secant(near, false)};
  };
  if (n == 2) return {secant(0, true), secant(0, false)};
  if (j == 0) return one_sided(0, true);
  if (j + 1 == n) return one_sided(n - 2, false);
  if (side == RateSide::kForward && j + 2 < n) return one_sided(j, true);
  if (side == RateSide::kBackward && j >= 2) return one_sided(j - 1, false);
  const double before = step(j - 1), after = step(j);
  if (before > 4.0 * after) return one_sided(j, true);
  if (after > 4.0 * before) return one_sided(j - 1, false);
  return rates(j - 1, j, true);
}

inline WheelRates WheelRatesAt(const std::vector<EncoderSample>& odometry, size_t j,
                               RateSide side = RateSide::kCentred) {
  return WheelRatesAt(
      odometry, j, [&](size_t i) { return odometry[i].t_s; }, side);
}

// The angle at t on [e0, e1] from the angles a0, a1 and rates m0, m1 there, with s = (t − e0)/Δ,
// Δ = e1 − e0:  α = a0 + (3s² − 2s³)·(a1 − a0) + Δ·[(s³ − 2s² + s)·m0 + (s³ − s²)·m1].
// Rates m0 = m1 = (a1 − a0)/Δ give the line. Outside [e0, e1] it goes on along the end's tangent
// (latent times may cross a sample during a solve, and a cubic would run away; the caller
// re-brackets after it).
template <typename T>
T HermiteWheelAngle(const T& t_s, const T& e0_s, const T& e1_s, double a0_rad, double a1_rad,
                    double m0_rad_s, double m1_rad_s) {
  if (t_s < e0_s) return T(a0_rad) + (t_s - e0_s) * m0_rad_s;
  if (t_s > e1_s) return T(a1_rad) + (t_s - e1_s) * m1_rad_s;
  const T span = e1_s - e0_s;
  const T s = (t_s - e0_s) / span;
  const T s2 = s * s;
  const T s3 = s2 * s;
  return T(a0_rad) + (3.0 * s2 - 2.0 * s3) * (a1_rad - a0_rad) +
         span * ((s3 - 2.0 * s2 + s) * m0_rad_s + (s3 - s2) * m1_rad_s);
}

// ∂α/∂t, ∂α/∂e0 and ∂α/∂e1 of HermiteWheelAngle (the rates held fixed).
struct HermitePartials {
  double t = 0.0;
  double e0 = 0.0;
  double e1 = 0.0;
};

inline HermitePartials HermiteWheelAnglePartials(double t_s, double e0_s, double e1_s,
                                                 double a0_rad, double a1_rad, double m0_rad_s,
                                                 double m1_rad_s) {
  if (t_s < e0_s) return {m0_rad_s, -m0_rad_s, 0.0};
  if (t_s > e1_s) return {m1_rad_s, 0.0, -m1_rad_s};
  const double span = e1_s - e0_s;
  const double s = (t_s - e0_s) / span;
  const double s2 = s * s, s3 = s2 * s;
  const double rate_part = (s3 - 2.0 * s2 + s) * m0_rad_s + (s3 - s2) * m1_rad_s;
  const double d_ds =
      (6.0 * s - 6.0 * s2) * (a1_rad - a0_rad) +
      span * ((3.0 * s2 - 4.0 * s + 1.0) * m0_rad_s + (3.0 * s2 - 2.0 * s) * m1_rad_s);
  // ∂s/∂t = 1/Δ, ∂s/∂e0 = (s − 1)/Δ, ∂s/∂e1 = −s/Δ; ∂Δ/∂e0 = −1, ∂Δ/∂e1 = 1.
  return {d_ds / span, d_ds * (s - 1.0) / span - rate_part, -d_ds * s / span + rate_part};
}

// The cubic pays where polls are 75 ms apart or more. The line misses α''·h²/8 at a poll period h;
// the cubic's rates, from stamps scattered by σ, err by about σ·α'/h and move the curve by a fifth
// of that times h. With speeds that change over half a second and a few ms of scatter, the two
// cross near 50 ms.
inline bool CubicBetweenPolls(double encoder_period_s) { return encoder_period_s >= 0.075; }

// Cumulative wheel angles at t in the segment [odometry[j], odometry[j + 1]] (sample j itself when
// t is its time or j is the last sample), on the cubic or the line.
inline void WheelAnglesInSegment(const std::vector<EncoderSample>& odometry, size_t j, double t_s,
                                 bool cubic, double* left_rad, double* right_rad) {
  const EncoderSample& a = odometry[j];
  if (t_s == a.t_s || j + 1 >= odometry.size()) {
    *left_rad = a.left_rad;
    *right_rad = a.right_rad;
    return;
  }
  const EncoderSample& b = odometry[j + 1];
  if (!cubic) {
    const double f = (t_s - a.t_s) / (b.t_s - a.t_s);
    *left_rad = a.left_rad + f * (b.left_rad - a.left_rad);
    *right_rad = a.right_rad + f * (b.right_rad - a.right_rad);
    return;
  }
  const WheelRates m0 = WheelRatesAt(odometry, j), m1 = WheelRatesAt(odometry, j + 1);
  *left_rad = HermiteWheelAngle(t_s, a.t_s, b.t_s, a.left_rad, b.left_rad, m0.left, m1.left);
  *right_rad = HermiteWheelAngle(t_s, a.t_s, b.t_s, a.right_rad, b.right_rad, m0.right, m1.right);
}

}  // namespace calib

#endif  // CALIB_CORE_TIMING_WHEEL_ANGLE_SPLINE_H_
