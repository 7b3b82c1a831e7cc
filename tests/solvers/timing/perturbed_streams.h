#ifndef CALIB_TESTS_SOLVERS_TIMING_PERTURBED_STREAMS_H_
#define CALIB_TESTS_SOLVERS_TIMING_PERTURBED_STREAMS_H_

#include <calib/core/laser/laser_simulator.h>

#include <algorithm>
#include <cmath>
#include <random>

// Logging artefacts added to SimulateLaserStreams output (whose stamps are the true times), until
// the logging simulator of core/timing/logging_model.h is merged.
namespace calib::test {

// Encoder stamps scattered by N(0, σ²) (kept increasing).
inline void ScatterEncoderStamps(LaserStreams* streams, double sigma_s, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, sigma_s);
  for (EncoderSample& s : streams->odometry) s.t_s += normal(rng);
  std::sort(streams->odometry.begin(), streams->odometry.end(),
            [](const EncoderSample& a, const EncoderSample& b) { return a.t_s < b.t_s; });
}

// Sensor stamps scattered by N(0, σ²) plus an offset: a sample stamped s was taken at s − offset.
inline void ScatterSensorStamps(LaserStreams* streams, double sigma_s, double offset_s,
                                unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, sigma_s);
  for (StampedPose& p : streams->sensor_poses) p.t_s += offset_s + normal(rng);
  std::sort(streams->sensor_poses.begin(), streams->sensor_poses.end(),
            [](const StampedPose& a, const StampedPose& b) { return a.t_s < b.t_s; });
}

// A logger that, every `period_s` (+ N(0, jitter²)), records the latest sensor sample with its own
// time as the stamp: samples picked up twice repeat their values, samples never picked up vanish.
inline void PickUpStamps(LaserStreams* streams, double period_s, double jitter_s, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, jitter_s);
  const std::vector<StampedPose> taken = streams->sensor_poses;
  std::vector<StampedPose> logged;
  size_t latest = 0;
  for (double tick = taken.front().t_s + 0.37 * period_s; tick < taken.back().t_s;
       tick += period_s) {
    const double stamp =
        std::max(tick + normal(rng), logged.empty() ? -1e300 : logged.back().t_s + 1e-6);
    while (latest + 1 < taken.size() && taken[latest + 1].t_s <= stamp) ++latest;
    if (taken[latest].t_s > stamp) continue;
    logged.push_back(StampedPose{stamp, taken[latest].world_T_sensor});
  }
  streams->sensor_poses = logged;
}

}  // namespace calib::test

#endif  // CALIB_TESTS_SOLVERS_TIMING_PERTURBED_STREAMS_H_
