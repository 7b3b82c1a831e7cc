#include <calib/core/bearing/bearing_log_io.h>
#include <calib/solvers/bearing/bearing_crlb.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace calib {

StatusOr<BearingBound> BearingCramerRaoBound(const BearingLog& log, const BearingSimTruth& truth,
                                             const BearingNoise& noise) {
  CALIB_RETURN_IF_ERROR(ValidateBearingLog(log));
  if (!(noise.bearing_sigma_rad > 0.0) || !(noise.encoder_k >= 0.0)) {
    return Status::InvalidInput("the bound needs σβ > 0 and K ≥ 0");
  }
  const std::vector<BearingRunNodes> nodes = BearingNodes(log);
  const double delta_r = truth.metric.delta_r;
  std::vector<std::vector<Pose2d>> poses(log.runs.size());
  for (size_t i = 0; i < log.runs.size(); ++i) {
    const auto run = std::find_if(truth.runs.begin(), truth.runs.end(),
                                  [&](const BearingRunTruth& t) { return t.id == log.runs[i].id; });
    if (run == truth.runs.end() ||
        run->world_T_robot_at_bearings.size() != log.runs[i].bearings.size()) {
      return Status::InvalidInput("the truth does not match run " + std::to_string(log.runs[i].id));
    }
    for (int bearing : nodes[i].bearing) {
      Pose2d p = bearing < 0 ? run->world_T_robot_start : run->world_T_robot_at_bearings[bearing];
      p.head<2>() /= delta_r;  // Gauge units (δR ≡ 1).
      poses[i].push_back(p);
    }
  }
  BearingAdjustmentOptions options;
  options.loss = RobustLoss::kNone;
  // With K = 0 the odometry is exact up to the covariance floor of BearingAdjustmentOptions.
  BearingProblem problem(log, truth.params, poses, noise, options);

  CALIB_ASSIGN_OR_RETURN(const BearingEstimateCovariance cov,
                         EstimateCovariance(problem, log, truth.params,
                                            /*loss_correction=*/false));
  BearingBound bound;
  bound.covariance = cov.covariance;
  bound.has_metric = cov.has_metric;
  bound.metric_covariance = cov.metric_covariance;
  bound.metric_stddev = bound.metric_covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  bound.stddev = bound.covariance.diagonal().cwiseMax(0.0).cwiseSqrt();
  return bound;
}

}  // namespace calib
