#ifndef CALIB_TESTS_SOLVERS_TIMING_JITTERED_LOG_H_
#define CALIB_TESTS_SOLVERS_TIMING_JITTERED_LOG_H_

#include <calib/core/laser/laser_simulator.h>
#include <calib/core/random.h>

#include <algorithm>
#include <vector>

namespace calib {

// A simulated tuple log whose odometry was integrated between boundary stamps off by
// ε ~ N(0, jitter²): the wheel increments are re-read from the finely recorded wheel steps over
// [t_k + ε_k, t_{k+1} + ε_{k+1}] while the scan displacements keep the true boundaries. The
// result carries mean speeds only (no steps), like a tuple log.
inline LaserLog JitteredTupleLog(LaserSimOptions sim, double jitter_s) {
  sim.record_steps = 40;
  LaserLog log = SimulateLaserLog(sim);
  const std::vector<LaserInterval>& fine = log.intervals;
  // The cumulative wheel angles at every step boundary.
  std::vector<double> times = {fine.front().start_s};
  std::vector<Eigen::Vector2d> angles = {Eigen::Vector2d::Zero()};
  for (const LaserInterval& interval : fine) {
    for (const WheelStep& step : interval.steps) {
      times.push_back(times.back() + step.duration_s);
      angles.push_back(angles.back() + Eigen::Vector2d(step.left_rad, step.right_rad));
    }
  }
  const auto angle_at = [&](double t) {
    t = std::clamp(t, times.front(), times.back());
    const size_t i = std::min<size_t>(
        std::upper_bound(times.begin(), times.end(), t) - times.begin(), times.size() - 1);
    const double w = (t - times[i - 1]) / (times[i] - times[i - 1]);
    return Eigen::Vector2d((1 - w) * angles[i - 1] + w * angles[i]);
  };
  Random random(sim.seed + 7919);
  std::vector<double> stamps;
  for (const LaserInterval& interval : fine) stamps.push_back(interval.start_s);
  stamps.push_back(fine.back().start_s + fine.back().duration_s);
  for (double& t : stamps) t += jitter_s * random.Normal();
  std::vector<LaserInterval> jittered = fine;
  for (size_t k = 0; k < jittered.size(); ++k) {
    LaserInterval& interval = jittered[k];
    interval.steps.clear();
    interval.start_s = stamps[k];
    interval.duration_s = stamps[k + 1] - stamps[k];
    const Eigen::Vector2d increment = angle_at(stamps[k + 1]) - angle_at(stamps[k]);
    interval.left_speed = increment(0) / interval.duration_s;
    interval.right_speed = increment(1) / interval.duration_s;
  }
  log.intervals = std::move(jittered);
  return log;
}

}  // namespace calib

#endif  // CALIB_TESTS_SOLVERS_TIMING_JITTERED_LOG_H_
