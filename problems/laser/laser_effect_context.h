#ifndef CALIB_PROBLEMS_LASER_LASER_EFFECT_CONTEXT_H_
#define CALIB_PROBLEMS_LASER_LASER_EFFECT_CONTEXT_H_

#include <calib/core/laser/laser_log.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

// What the candidate effects of laser_effect_residual.h need beyond each interval: the wheel
// speeds at its ends, the radius change time and the reference speed.
namespace calib {

// How the wheel speeds behave at interval boundaries, where the time offset and the longitudinal
// slip act.
enum class BoundarySpeedModel {
  // Constant within each interval, jumping at boundaries (the simulator with
  // speed_time_constant_s = 0): exact for such logs.
  kPiecewiseConstant,
  // Smooth: the instantaneous speed at a boundary is the derivative of the polynomial through
  // the cumulative wheel angles at up to seven neighbouring boundaries (6th order; centred, it
  // gives the mean of the two sides at an isolated jump, like the piecewise model at γ → 0).
  kSmooth,
};

// Wheel speeds (φ_l, φ_r), rad/s, just before and just after an interval end. Piecewise: the
// neighbouring constant speeds; smooth: both the same estimate of the instantaneous speed.
struct BoundarySpeeds {
  Eigen::Vector2d before = Eigen::Vector2d::Zero();
  Eigen::Vector2d after = Eigen::Vector2d::Zero();
};

// What an interval's effects need beyond the interval itself.
struct LaserEffectContext {
  const LaserInterval* interval = nullptr;
  BoundarySpeeds start;  // At t_k.
  BoundarySpeeds end;    // At t_{k+1}.
  // Radius change time relative to the interval start, t_c − t_k (s): +inf never, −inf (or any
  // value ≤ 0) the whole interval runs on the changed radii.
  double change_offset_s = std::numeric_limits<double>::infinity();
  // φ_ref of the speed-dependent radius (rad/s): the log's median wheel speed magnitude, so that
  // r keeps meaning the radius at typical speeds.
  double reference_speed = 0.0;
};

// Weights w_j of the derivative at x0 of the polynomial through (x_j, y_j): y'(x0) ≈ Σ w_j·y_j.
inline std::vector<double> DerivativeWeights(const std::vector<double>& nodes, double x0) {
  const size_t n = nodes.size();
  std::vector<double> weights(n, 0.0);
  for (size_t j = 0; j < n; ++j) {
    // L_j'(x0) = Σ_{m≠j} 1/(x_j − x_m) · Π_{l≠j,m} (x0 − x_l)/(x_j − x_l).
    for (size_t m = 0; m < n; ++m) {
      if (m == j) continue;
      double term = 1.0 / (nodes[j] - nodes[m]);
      for (size_t l = 0; l < n; ++l) {
        if (l != j && l != m) term *= (x0 - nodes[l]) / (nodes[j] - nodes[l]);
      }
      weights[j] += term;
    }
  }
  return weights;
}

// The same weights at the node x0 = nodes[k], in O(n²) from the barycentric weights
// b_j = 1/Π_{l≠j}(x_j − x_l): L_j'(x_k) = (b_j/b_k)/(x_k − x_j) for j ≠ k, and
// L_k'(x_k) = Σ_{l≠k} 1/(x_k − x_l).
inline std::vector<double> NodeDerivativeWeights(const std::vector<double>& nodes, size_t k) {
  const size_t n = nodes.size();
  std::vector<double> barycentric(n, 1.0);
  for (size_t j = 0; j < n; ++j) {
    double product = 1.0;
    for (size_t l = 0; l < n; ++l) {
      if (l != j) product *= nodes[j] - nodes[l];
    }
    barycentric[j] = 1.0 / product;
  }
  std::vector<double> weights(n, 0.0);
  for (size_t j = 0; j < n; ++j) {
    if (j == k) continue;
    const double difference = nodes[k] - nodes[j];
    weights[j] = barycentric[j] / (barycentric[k] * difference);
    weights[k] += 1.0 / difference;
  }
  return weights;
}

namespace context_internal {

// The interval's wheel speeds at its start and at its end: of its first and last step, or its
// mean speeds without steps.
inline Eigen::Vector2d FirstSpeed(const LaserInterval& in) {
  if (in.steps.empty() || !(in.steps.front().duration_s > 0.0)) {
    return Eigen::Vector2d(in.left_speed, in.right_speed);
  }
  return Eigen::Vector2d(in.steps.front().left_rad, in.steps.front().right_rad) /
         in.steps.front().duration_s;
}
inline Eigen::Vector2d LastSpeed(const LaserInterval& in) {
  if (in.steps.empty() || !(in.steps.back().duration_s > 0.0)) {
    return Eigen::Vector2d(in.left_speed, in.right_speed);
  }
  return Eigen::Vector2d(in.steps.back().left_rad, in.steps.back().right_rad) /
         in.steps.back().duration_s;
}

// The smooth model: within each gap-free run, boundary times τ_i and cumulative wheel angles Φ_i;
// the speed at each boundary is the derivative of the polynomial through its neighbours.
inline void SetSmoothBoundarySpeeds(const std::vector<LaserInterval>& intervals,
                                    std::vector<LaserEffectContext>* contexts) {
  const size_t n = intervals.size();
  size_t run_start = 0;
  while (run_start < n) {
    size_t run_end = run_start + 1;
    while (run_end < n && !intervals[run_end].gap_before) ++run_end;
    const size_t count = run_end - run_start;  // Intervals; count + 1 boundaries.
    std::vector<double> times(count + 1);
    std::vector<Eigen::Vector2d> angles(count + 1, Eigen::Vector2d::Zero());
    times[0] = intervals[run_start].start_s;
    for (size_t i = 0; i < count; ++i) {
      const LaserInterval& in = intervals[run_start + i];
      times[i + 1] = times[i] + in.duration_s;
      Eigen::Vector2d rotation(in.left_speed * in.duration_s, in.right_speed * in.duration_s);
      if (!in.steps.empty()) {
        rotation.setZero();
        for (const WheelStep& step : in.steps)
          rotation += Eigen::Vector2d(step.left_rad, step.right_rad);
      }
      angles[i + 1] = angles[i] + rotation;
    }
    std::vector<Eigen::Vector2d> speeds(count + 1);
    for (size_t i = 0; i <= count; ++i) {
      // Up to seven nodes, as centred as the run allows (fewer did worse on smooth simulated
      // speeds: the 3-point estimate biased a time offset by −20 %, the 5-point by +5 %).
      const size_t width = std::min<size_t>(7, count + 1);
      size_t lo = i >= 3 ? i - 3 : 0;
      if (lo + width > count + 1) lo = count + 1 - width;
      std::vector<double> nodes(times.begin() + lo, times.begin() + lo + width);
      const std::vector<double> weights = NodeDerivativeWeights(nodes, i - lo);
      speeds[i].setZero();
      for (size_t j = 0; j < width; ++j) speeds[i] += weights[j] * angles[lo + j];
    }
    for (size_t i = 0; i < count; ++i) {
      LaserEffectContext& c = (*contexts)[run_start + i];
      c.start.before = c.start.after = speeds[i];
      c.end.before = c.end.after = speeds[i + 1];
    }
    run_start = run_end;
  }
}

}  // namespace context_internal

// The median wheel speed magnitude |φ| over both wheels of all intervals (0 for none).
inline double MedianWheelSpeed(const std::vector<LaserInterval>& intervals) {
  std::vector<double> magnitudes;
  for (const LaserInterval& in : intervals) {
    magnitudes.push_back(std::abs(in.left_speed));
    magnitudes.push_back(std::abs(in.right_speed));
  }
  double reference = 0.0;
  if (!magnitudes.empty()) {
    std::nth_element(magnitudes.begin(), magnitudes.begin() + magnitudes.size() / 2,
                     magnitudes.end());
    reference = magnitudes[magnitudes.size() / 2];
  }
  return reference;
}

// One context per interval. Intervals are neighbours unless the later one has gap_before; at a
// gap or the ends of the log the interval's own speed continues. `change_time_s` is the radius
// change on the log's clock (start_s), +inf for none.
inline std::vector<LaserEffectContext> BuildLaserEffectContexts(
    const std::vector<LaserInterval>& intervals, BoundarySpeedModel model,
    double change_time_s = std::numeric_limits<double>::infinity()) {
  const size_t n = intervals.size();
  std::vector<LaserEffectContext> contexts(n);
  const double reference = MedianWheelSpeed(intervals);
  for (size_t k = 0; k < n; ++k) {
    contexts[k].interval = &intervals[k];
    contexts[k].reference_speed = reference;
    contexts[k].change_offset_s = change_time_s - intervals[k].start_s;
    const bool has_previous = k > 0 && !intervals[k].gap_before;
    const bool has_next = k + 1 < n && !intervals[k + 1].gap_before;
    contexts[k].start.after = context_internal::FirstSpeed(intervals[k]);
    contexts[k].start.before = has_previous ? context_internal::LastSpeed(intervals[k - 1])
                                            : context_internal::FirstSpeed(intervals[k]);
    contexts[k].end.before = context_internal::LastSpeed(intervals[k]);
    contexts[k].end.after = has_next ? context_internal::FirstSpeed(intervals[k + 1])
                                     : context_internal::LastSpeed(intervals[k]);
  }
  if (model == BoundarySpeedModel::kPiecewiseConstant) return contexts;

  context_internal::SetSmoothBoundarySpeeds(intervals, &contexts);
  return contexts;
}

}  // namespace calib

#endif  // CALIB_PROBLEMS_LASER_LASER_EFFECT_CONTEXT_H_
