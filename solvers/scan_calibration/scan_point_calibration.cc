#include <calib/problems/positive_manifold.h>
#include <calib/solvers/common/parallel_chunks.h>
#include <calib/solvers/common/robust_covariance.h>
#include <calib/solvers/common/solver_options.h>
#include <calib/solvers/scan_calibration/scan_pair_lines.h>
#include <calib/solvers/scan_calibration/scan_point_calibration.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

namespace calib {
namespace {

constexpr int kMinPairs = 12;

// The earliest and the latest beam's time (a mirrored scan's beams run backwards in time).
double BeamTime(const ScanPointInput& in, int i, bool latest) {
  const LaserScan& s = *in.scans[i];
  const double last = in.first_beam_time_s[i] + s.SweepSeconds();
  return latest ? std::max(last, in.first_beam_time_s[i]) : std::min(last, in.first_beam_time_s[i]);
}

Status CheckInput(const ScanPointInput& in) {
  if (in.encoders == nullptr || in.encoders->size() < 2) {
    return Status::InvalidInput(in.source + ": the scan-point calibration needs the wheel angles");
  }
  if (in.first_beam_time_s.size() != in.scans.size()) {
    return Status::InvalidInput(in.source + ": one first-beam time per scan is needed");
  }
  for (size_t i = 0; i < in.scans.size(); ++i) {
    const double t = in.first_beam_time_s[i];
    if (!std::isfinite(t) || !std::isfinite(in.scans[i]->time_increment_s) ||
        (i > 0 && !(t > in.first_beam_time_s[i - 1]))) {
      return Status::InvalidInput(in.source + ": scan (record " +
                                  std::to_string(in.scans[i]->record) +
                                  "): its time is not finite or does not follow the previous "
                                  "scan's");
    }
  }
  return Status::Ok();
}

// world_T_base at each scan's first beam through the wheels (identity at the first scan).
std::vector<Pose2d> DeadReckonScans(const ScanPointInput& in, const OdometryParams& odometry) {
  std::vector<Pose2d> poses(in.scans.size(), Pose2d::Zero());
  for (size_t i = 1; i < poses.size(); ++i) {
    const PairTimeline step =
        MakePairTimeline(*in.encoders, in.first_beam_time_s[i - 1], in.first_beam_time_s[i]);
    poses[i] = Compose(poses[i - 1], KnotPoses(step, odometry).back());
  }
  return poses;
}

// Each scan paired with the first later one pair_distance_m or pair_angle_rad away, spread
// evenly down to max_pairs.
std::vector<ScanPair> SelectPairs(const ScanPointInput& in, const LaserCalibration& c,
                                  const ScanPointOptions& o) {
  const std::vector<Pose2d> world_T_base = DeadReckonScans(in, c.odometry);
  const double first_s = in.encoders->front().t_s, last_s = in.encoders->back().t_s;
  const int n = static_cast<int>(in.scans.size());
  std::vector<std::pair<int, int>> candidates;
  for (int i = 0; i < n; ++i) {
    if (BeamTime(in, i, false) < first_s) continue;
    int chosen = -1;
    for (int j = i + 1;
         j < n && in.first_beam_time_s[j] - in.first_beam_time_s[i] <= o.max_pair_span_s; ++j) {
      const Pose2d m =
          SensorMotionFromRobotMotion(c.base_T_sensor, Between(world_T_base[i], world_T_base[j]));
      const double d = m.head<2>().norm(), a = std::abs(m(2));
      if (d >= o.pair_distance_m || a >= o.pair_angle_rad) {
        chosen = j;
        break;
      }
      if (d >= o.min_pair_distance_m || a >= o.min_pair_angle_rad) chosen = j;
    }
    if (chosen >= 0 && BeamTime(in, chosen, true) <= last_s) candidates.emplace_back(i, chosen);
  }
  const size_t keep = std::min<size_t>(candidates.size(), std::max(1, o.max_pairs));
  // A scan is the reference of one pair and the current scan of others up to a span later.
  double span = 0.0;
  for (size_t k = 0; k < keep; ++k) {
    const auto& [i, j] = candidates[k * candidates.size() / keep];
    span += (j - i) * static_cast<double>(keep) / candidates.size();
  }
  const int per_cluster =
      std::max(1, std::min(static_cast<int>(std::ceil(4.0 * span / std::max<size_t>(1, keep))),
                           static_cast<int>(keep) / std::max(1, o.min_clusters)));
  std::vector<ScanPair> pairs(keep);
  for (size_t k = 0; k < keep; ++k) {
    const auto& [i, j] = candidates[k * candidates.size() / keep];
    pairs[k].reference = i;
    pairs[k].current = j;
    pairs[k].cluster = static_cast<int>(k) / per_cluster;
    pairs[k].timeline = MakePairTimeline(
        *in.encoders, BeamTime(in, i, false) - o.max_time_offset_s,
        std::max(BeamTime(in, i, true), BeamTime(in, j, true)) + o.max_time_offset_s);
  }
  return pairs;
}

// σ̂ = 1.4826·median(|d|/√v) over every pair's lines.
double RobustRangeSigma(const std::vector<ScanPair>& pairs) {
  std::vector<double> z;
  for (const ScanPair& p : pairs) {
    for (size_t i = 0; i < p.distance_m.size(); ++i) {
      z.push_back(std::abs(p.distance_m[i]) / std::sqrt(p.variance_factor[i]));
    }
  }
  if (z.empty()) return 0.0;
  auto middle = z.begin() + z.size() / 2;
  std::nth_element(z.begin(), middle, z.end());
  return 1.4826 * *middle;
}

// The six parameters and the sensor's time offset.
using ScanPointParams = Eigen::Matrix<double, kNumLaserParams + 1, 1>;
constexpr int kTimeOffset = kNumLaserParams;

// Finds and weights every pair's lines at `p`; the lines of the pairs that keep enough.
StatusOr<int> FindLines(const ScanPointInput& in, const ScanPointParams& p,
                        const ScanPointOptions& o, std::vector<ScanPair>* pairs,
                        double* range_sigma_m, double* inlier_fraction) {
  const LaserCalibration c = LaserCalibration::FromVector(p.head<kNumLaserParams>());
  std::vector<Status> status(pairs->size());
  ParallelChunks(pairs->size(), o.num_threads, 8, [&](int, size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) {
      status[k] = FindPairLines(in, c, p(kTimeOffset), o, &(*pairs)[k]);
    }
  });
  for (const Status& s : status) CALIB_RETURN_IF_ERROR(s);
  *range_sigma_m = RobustRangeSigma(*pairs);
  if (!(*range_sigma_m > 0.0)) {
    return Status::NotObservable(in.source + ": no scan pair has correspondences");
  }
  int found = 0, kept = 0;
  for (ScanPair& pair : *pairs) {
    found += static_cast<int>(pair.geometry.lines.size());
    const int lines = WeighPairLines(*range_sigma_m, o, &pair);
    if (lines < o.min_lines_per_pair) pair.geometry.lines.clear();
    kept += static_cast<int>(pair.geometry.lines.size());
  }
  *inlier_fraction = found > 0 ? static_cast<double>(kept) / found : 0.0;
  return kept;
}

// H = Σ JᵀJ and each cluster's gradient Σ Jᵀr of the weighted residuals, over the first
// `estimated` parameters (the time offset last).
struct Sums {
  explicit Sums(int estimated) : hessian(Eigen::MatrixXd::Zero(estimated, estimated)) {}
  Eigen::MatrixXd hessian;
  std::vector<Eigen::VectorXd> cluster_gradient;
  double cost = 0.0;  // Σ r² of the weighted residuals.
  int residuals = 0;
};

Sums Linearize(const std::vector<ScanPair>& pairs,
               const std::vector<std::unique_ptr<ceres::CostFunction>>& costs,
               const ScanPointParams& p, int estimated) {
  Sums s(estimated);
  const double* parameters[3] = {p.data(), p.data() + 3, p.data() + kTimeOffset};
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (costs[k] == nullptr) continue;
    const int n = static_cast<int>(pairs[k].geometry.lines.size());
    Eigen::VectorXd r(n), j2(n);
    Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> j0(n, 3), j1(n, 3);
    double* jacobians[3] = {j0.data(), j1.data(), j2.data()};
    if (!costs[k]->Evaluate(parameters, r.data(), jacobians)) continue;
    Eigen::MatrixXd j(n, kNumLaserParams + 1);
    j << j0, j1, j2;
    const auto used = j.leftCols(estimated);
    const int cluster = pairs[k].cluster;
    if (static_cast<int>(s.cluster_gradient.size()) <= cluster) {
      s.cluster_gradient.resize(cluster + 1, Eigen::VectorXd::Zero(estimated));
    }
    s.hessian += used.transpose() * used;
    s.cluster_gradient[cluster] += used.transpose() * r;
    s.cost += r.squaredNorm();
    s.residuals += n;
  }
  return s;
}

// The cluster sandwich, held to at least the independent-noise model.
Status Covariance(const Sums& s, ScanPointCalibration* out) {
  const int d = static_cast<int>(s.hessian.rows());
  Eigen::MatrixXd meat = Eigen::MatrixXd::Zero(d, d);
  int clusters = 0;
  for (const Eigen::VectorXd& g : s.cluster_gradient) {
    if (g.isZero(0.0)) continue;
    meat += g * g.transpose();
    ++clusters;
  }
  out->clusters = clusters;
  CALIB_ASSIGN_OR_RETURN(const auto sandwich, SandwichCovariance<Eigen::MatrixXd>(
                                                  s.hessian, meat, clusters, clusters - d));
  const Eigen::MatrixXd model = s.hessian.inverse() * s.cost / (s.residuals - d);
  const DominatingCovarianceResult dominating = DominatingCovariance(model, sandwich.covariance);
  out->covariance = dominating.covariance.topLeftCorner<kNumLaserParams, kNumLaserParams>();
  out->correlation_inflation = dominating.largest_ratio;
  out->stddev = out->covariance.diagonal().cwiseSqrt();
  out->time_offset_stddev_s =
      d > kNumLaserParams ? std::sqrt(dominating.covariance(kTimeOffset, kTimeOffset)) : 0.0;
  return Status::Ok();
}

// One Ceres solve over the pairs' fixed lines and weights.
Status SolveRound(std::vector<ScanPair>* pairs, const ScanPointOptions& o, ScanPointParams* p,
                  ScanPointCalibration* out) {
  std::vector<std::unique_ptr<ceres::CostFunction>> costs(pairs->size());
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  PositiveManifold<3> positive;
  double* blocks[3] = {p->data(), p->data() + 3, p->data() + kTimeOffset};
  for (size_t k = 0; k < pairs->size(); ++k) {
    if ((*pairs)[k].geometry.lines.empty()) continue;
    costs[k].reset(ScanPairResidual::Create(&(*pairs)[k].geometry));
    problem.AddResidualBlock(costs[k].get(), nullptr, blocks[0], blocks[1], blocks[2]);
  }
  problem.SetManifold(blocks[0], &positive);
  if (o.estimate_time_offset) {
    problem.SetParameterLowerBound(blocks[2], 0, -o.max_time_offset_s);
    problem.SetParameterUpperBound(blocks[2], 0, o.max_time_offset_s);
  } else {
    problem.SetParameterBlockConstant(blocks[2]);
  }
  SolverSettings settings;
  settings.max_iterations = 50;
  settings.num_threads = o.num_threads;
  settings.function_tolerance = 1e-9;
  ceres::Solver::Summary summary;
  CALIB_RETURN_IF_ERROR(Solve(settings, "the scan-point refinement", &problem, &summary));
  const Sums sums =
      Linearize(*pairs, costs, *p, kNumLaserParams + (o.estimate_time_offset ? 1 : 0));
  out->lines = sums.residuals;
  return Covariance(sums, out);
}

// The rounds of correspondences and solves from `initial`.
StatusOr<ScanPointCalibration> Refine(const ScanPointInput& input, const LaserCalibration& initial,
                                      const ScanPointOptions& options) {
  std::vector<ScanPair> pairs = SelectPairs(input, initial, options);
  if (static_cast<int>(pairs.size()) < kMinPairs) {
    return Status::NotObservable(input.source + ": only " + std::to_string(pairs.size()) +
                                 " pairs of scans with motion between them: the scan-point "
                                 "calibration needs at least " +
                                 std::to_string(kMinPairs));
  }
  ScanPointCalibration out;
  ScanPointParams p;
  p << initial.ToVector(), 0.0;
  for (out.rounds = 1; out.rounds <= options.max_rounds; ++out.rounds) {
    CALIB_ASSIGN_OR_RETURN(const int lines, FindLines(input, p, options, &pairs, &out.range_sigma_m,
                                                      &out.inlier_fraction));
    out.pairs = 0;
    for (const ScanPair& pair : pairs) out.pairs += !pair.geometry.lines.empty();
    if (out.pairs < kMinPairs || lines < 10 * kNumLaserParams) {
      return Status::NotObservable(input.source + ": only " + std::to_string(out.pairs) +
                                   " scan pairs overlap enough for the scan-point calibration");
    }
    const ScanPointParams before = p;
    CALIB_RETURN_IF_ERROR(SolveRound(&pairs, options, &p, &out));
    // Relative to σ, or to the parameters where σ is at the floats' resolution (clean scans).
    const LaserParamVector step = (p - before).head<kNumLaserParams>();
    const double moved = step.cwiseQuotient(out.stddev).cwiseAbs().maxCoeff();
    const double relative =
        step.cwiseQuotient(p.head<kNumLaserParams>().cwiseAbs().array().max(0.01).matrix())
            .cwiseAbs()
            .maxCoeff();
    if (out.rounds >= 2 && (moved < options.tolerance_sigmas || relative < 1e-6)) {
      out.converged = true;
      break;
    }
  }
  out.rounds = std::min(out.rounds, options.max_rounds);
  out.estimate = LaserCalibration::FromVector(p.head<kNumLaserParams>());
  // The mounting angle may have run a whole turn from a poor start: report it in (−π, π].
  out.estimate.base_T_sensor(2) = WrapAngle(out.estimate.base_T_sensor(2));
  out.time_offset_s = p(kTimeOffset);
  if (!out.converged) {
    out.warnings.push_back("the scan-point refinement was still moving after " +
                           std::to_string(options.max_rounds) + " rounds of correspondences");
  }
  if (out.inlier_fraction < 0.5) {
    out.warnings.push_back("only " + std::to_string(static_cast<int>(100 * out.inlier_fraction)) +
                           " % of the point correspondences fit their lines: the scans may not "
                           "overlap, or the scene moves");
  }
  return out;
}

}  // namespace

StatusOr<ScanPointCalibration> CalibrateOnScanPoints(const ScanPointInput& input,
                                                     const LaserCalibration& initial,
                                                     const ScanPointOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  CALIB_RETURN_IF_ERROR(CheckInput(input));
  LaserCalibration from = initial;
  if (options.warm_start) {
    // Consecutive scans first: their motion is short, so a start tens of per cent off still
    // places their points within reach of the right lines.
    ScanPointOptions near = options;
    near.warm_start = false;
    near.pair_distance_m = near.pair_angle_rad = 0.05;
    near.min_pair_distance_m = near.min_pair_angle_rad = 0.005;
    near.estimate_time_offset = false;
    near.max_rounds = 6;
    const StatusOr<ScanPointCalibration> warm = Refine(input, initial, near);
    if (warm.ok()) from = warm->estimate;
  }
  CALIB_ASSIGN_OR_RETURN(ScanPointCalibration out, Refine(input, from, options));
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace calib
