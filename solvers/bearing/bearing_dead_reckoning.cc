#include <calib/core/timing/encoder_integration.h>
#include <calib/solvers/bearing/bearing_dead_reckoning.h>

namespace calib {
namespace {

struct WheelFactors {
  double right = 1.0, left = 1.0, base = 1.0;
};

// Chains the encoder displacements between the nodes from `start`.
std::vector<Pose2d> Reckon(const BearingLog& log, size_t run, const std::vector<double>& t_s,
                           const Pose2d& start, const WheelFactors& f) {
  const std::vector<EncoderSample>& odometry = log.runs[run].odometry;
  std::vector<Pose2d> poses = {start};
  for (size_t k = 1; k < t_s.size(); ++k) {
    poses.push_back(Compose(poses.back(),
                            IntegrateEncoders(odometry, t_s[k - 1], t_s[k], log.meta.wheel_radius_m,
                                              log.meta.wheelbase_m, f.right, f.left, f.base)));
  }
  return poses;
}

}  // namespace

BearingPaths BearingDeadReckoning(const BearingLog& log, const BearingCalibrationResult& result) {
  BearingPaths paths;
  paths.metric = result.has_metric;
  // Gauge lengths are δR metres: metres = gauge × δR.
  const double scale = result.has_metric ? result.metric.delta_r : 1.0;
  WheelFactors calibrated;
  if (result.has_metric) {
    calibrated = {result.metric.delta_r, result.metric.delta_l, result.metric.delta_b};
  } else {
    calibrated = {1.0, result.estimate.delta,
                  1.0 / (log.meta.wheelbase_m * result.estimate.xi_per_m)};
  }
  for (size_t i = 0;
       i < log.runs.size() && i < result.poses.size() && i < result.node_times_s.size(); ++i) {
    const std::vector<double>& t = result.node_times_s[i];
    if (t.empty() || t.size() != result.poses[i].size() || log.runs[i].odometry.empty()) continue;
    BearingRunPaths run;
    run.run = log.runs[i].id;
    run.index = i;
    run.t_s = t;
    // A start node without a bearing comes first when there is one more node than bearings.
    const int first = i < result.residuals_rad.size() && t.size() > result.residuals_rad[i].size();
    for (size_t k = 0; k < t.size(); ++k) run.bearing.push_back(static_cast<int>(k) - first);
    for (const Pose2d& p : result.poses[i])
      run.adjusted.emplace_back(scale * p(0), scale * p(1), p(2));
    run.nominal = Reckon(log, i, t, run.adjusted.front(), WheelFactors{});
    run.calibrated = Reckon(log, i, t, run.adjusted.front(), calibrated);
    for (size_t k = 0; k < t.size(); ++k) {
      const double dt = k > 0 ? t[k] - t[k - 1] : 0.0;
      const Pose2d step = k > 0 && dt > 0 ? Between(run.calibrated[k - 1], run.calibrated[k])
                                          : Pose2d::Zero().eval();
      run.v_mps.push_back(dt > 0 ? step(0) / dt : 0.0);
      run.omega_radps.push_back(dt > 0 ? step(2) / dt : 0.0);
    }
    paths.runs.push_back(std::move(run));
  }
  return paths;
}

}  // namespace calib
