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
  const double last =
      in.first_beam_time_s[i] + s.time_increment_s * (static_cast<double>(s.ranges_m.size()) - 1.0);
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
    pairs[k].timeline = MakePairTimeline(*in.encoders, BeamTime(in, i, false),
                                         std::max(BeamTime(in, i, true), BeamTime(in, j, true)));
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

// Finds and weights every pair's lines at `c`; the lines of the pairs that keep enough.
StatusOr<int> FindLines(const ScanPointInput& in, const LaserCalibration& c,
                        const ScanPointOptions& o, std::vector<ScanPair>* pairs,
                        double* range_sigma_m, double* inlier_fraction) {
  std::vector<Status> status(pairs->size());
  ParallelChunks(pairs->size(), o.num_threads, 8, [&](int, size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) status[k] = FindPairLines(in, c, o, &(*pairs)[k]);
  });
  for (const Status& s : status) CALIB_RETURN_IF_ERROR(s);
  *range_sigma_m = RobustRangeSigma(*pairs);
  if (!(*range_sigma_m > 0.0)) {
    return Status::NotObservable(in.source + ": no scan pair has correspondences");
  }
  int found = 0, kept = 0;
  for (ScanPair& p : *pairs) {
    found += static_cast<int>(p.geometry.lines.size());
    const int lines = WeighPairLines(*range_sigma_m, o, &p);
    if (lines < o.min_lines_per_pair) p.geometry.lines.clear();
    kept += static_cast<int>(p.geometry.lines.size());
  }
  *inlier_fraction = found > 0 ? static_cast<double>(kept) / found : 0.0;
  return kept;
}

struct Sums {
  LaserParamMatrix hessian = LaserParamMatrix::Zero();
  std::vector<LaserParamVector> cluster_gradient;
  double cost = 0.0;  // Σ r² of the weighted residuals.
  int residuals = 0;
};

// H = Σ JᵀJ and each cluster's gradient Σ Jᵀr of the weighted residuals at `v`.
Sums Linearize(const std::vector<ScanPair>& pairs,
               const std::vector<std::unique_ptr<ceres::CostFunction>>& costs,
               const LaserParamVector& v) {
  Sums s;
  const double* parameters[2] = {v.data(), v.data() + 3};
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (costs[k] == nullptr) continue;
    const int n = static_cast<int>(pairs[k].geometry.lines.size());
    Eigen::VectorXd r(n);
    Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> j0(n, 3), j1(n, 3);
    double* jacobians[2] = {j0.data(), j1.data()};
    if (!costs[k]->Evaluate(parameters, r.data(), jacobians)) continue;
    Eigen::Matrix<double, Eigen::Dynamic, 6> j(n, 6);
    j << j0, j1;
    const int cluster = pairs[k].cluster;
    if (static_cast<int>(s.cluster_gradient.size()) <= cluster) {
      s.cluster_gradient.resize(cluster + 1, LaserParamVector::Zero());
    }
    s.hessian += j.transpose() * j;
    s.cluster_gradient[cluster] += j.transpose() * r;
    s.cost += r.squaredNorm();
    s.residuals += n;
  }
  return s;
}

// The cluster sandwich, held to at least the independent-noise model.
Status Covariance(const Sums& s, ScanPointCalibration* out) {
  LaserParamMatrix meat = LaserParamMatrix::Zero();
  int clusters = 0;
  for (const LaserParamVector& g : s.cluster_gradient) {
    if (g.isZero(0.0)) continue;
    meat += g * g.transpose();
    ++clusters;
  }
  out->clusters = clusters;
  CALIB_ASSIGN_OR_RETURN(
      const auto sandwich,
      SandwichCovariance<LaserParamMatrix>(s.hessian, meat, clusters, clusters - kNumLaserParams));
  const LaserParamMatrix model = s.hessian.inverse() * s.cost / (s.residuals - kNumLaserParams);
  const DominatingCovarianceResult d = DominatingCovariance(model, sandwich.covariance);
  out->covariance = d.covariance;
  out->correlation_inflation = d.largest_ratio;
  out->stddev = out->covariance.diagonal().cwiseSqrt();
  return Status::Ok();
}

// One Ceres solve over the pairs' fixed lines and weights.
Status SolveRound(std::vector<ScanPair>* pairs, const ScanPointOptions& o, LaserParamVector* v,
                  ScanPointCalibration* out) {
  std::vector<std::unique_ptr<ceres::CostFunction>> costs(pairs->size());
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  PositiveManifold<3> positive;
  for (size_t k = 0; k < pairs->size(); ++k) {
    if ((*pairs)[k].geometry.lines.empty()) continue;
    costs[k].reset(ScanPairResidual::Create(&(*pairs)[k].geometry));
    problem.AddResidualBlock(costs[k].get(), nullptr, v->data(), v->data() + 3);
  }
  problem.SetManifold(v->data(), &positive);
  SolverSettings settings;
  settings.max_iterations = 50;
  settings.num_threads = o.num_threads;
  settings.function_tolerance = 1e-9;
  ceres::Solver::Summary summary;
  CALIB_RETURN_IF_ERROR(Solve(settings, "the scan-point refinement", &problem, &summary));
  const Sums sums = Linearize(*pairs, costs, *v);
  out->lines = sums.residuals;
  return Covariance(sums, out);
}

}  // namespace

StatusOr<ScanPointCalibration> CalibrateOnScanPoints(const ScanPointInput& input,
                                                     const LaserCalibration& initial,
                                                     const ScanPointOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  CALIB_RETURN_IF_ERROR(CheckInput(input));
  std::vector<ScanPair> pairs = SelectPairs(input, initial, options);
  if (static_cast<int>(pairs.size()) < kMinPairs) {
    return Status::NotObservable(input.source + ": only " + std::to_string(pairs.size()) +
                                 " pairs of scans with motion between them: the scan-point "
                                 "calibration needs at least " +
                                 std::to_string(kMinPairs));
  }
  ScanPointCalibration out;
  LaserParamVector v = initial.ToVector();
  for (out.rounds = 1; out.rounds <= options.max_rounds; ++out.rounds) {
    const LaserCalibration current = LaserCalibration::FromVector(v);
    CALIB_ASSIGN_OR_RETURN(const int lines, FindLines(input, current, options, &pairs,
                                                      &out.range_sigma_m, &out.inlier_fraction));
    out.pairs = 0;
    for (const ScanPair& p : pairs) out.pairs += !p.geometry.lines.empty();
    if (out.pairs < kMinPairs || lines < 10 * kNumLaserParams) {
      return Status::NotObservable(input.source + ": only " + std::to_string(out.pairs) +
                                   " scan pairs overlap enough for the scan-point calibration");
    }
    const LaserParamVector before = v;
    CALIB_RETURN_IF_ERROR(SolveRound(&pairs, options, &v, &out));
    // Relative to σ, or to the parameters where σ is at the floats' resolution (clean scans).
    const double moved = ((v - before).cwiseQuotient(out.stddev)).cwiseAbs().maxCoeff();
    const double relative =
        ((v - before).cwiseQuotient(v.cwiseAbs().array().max(0.01).matrix())).cwiseAbs().maxCoeff();
    if (out.rounds >= 2 && (moved < options.tolerance_sigmas || relative < 1e-6)) {
      out.converged = true;
      break;
    }
  }
  out.rounds = std::min(out.rounds, options.max_rounds);
  out.estimate = LaserCalibration::FromVector(v);
  if (!out.converged) {
    out.warnings.push_back("the scan-point refinement was still moving after " +
                           std::to_string(options.max_rounds) + " rounds of correspondences");
  }
  if (out.inlier_fraction < 0.5) {
    out.warnings.push_back("only " + std::to_string(static_cast<int>(100 * out.inlier_fraction)) +
                           " % of the point correspondences fit their lines: the scans may not "
                           "overlap, or the scene moves");
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

}  // namespace calib
