#include <calib/solvers/scan_matching/line_noise_bias.h>
#include <calib/solvers/scan_matching/pl_icp.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <vector>

namespace calib {
namespace {

// One correspondence with its line: r = n·(R p + t − q_a). The foot of the point on the line
// sits at q_a + α (q_b − q_a), so ∂r/∂q_a = −(1 − α) n and ∂r/∂q_b = −α n.
struct LinePair {
  Correspondence c;
  Eigen::Vector2d normal;
  double alpha = 0.0;
  double residual_m = 0.0;
  double variance_factor = 1.0;  // Var(r)/σ² for independent range noise σ on the three points.
  bool inlier = true;
};

Eigen::Vector2d Rotate(double c, double s, const Eigen::Vector2d& v) {
  return {c * v.x() - s * v.y(), s * v.x() + c * v.y()};
}

void TransformPoints(const ScanPoints& scan, const Pose2d& pose,
                     std::vector<Eigen::Vector2d>* out) {
  const double c = std::cos(pose(2));
  const double s = std::sin(pose(2));
  out->resize(scan.points_m.size());
  for (size_t i = 0; i < scan.points_m.size(); ++i) {
    (*out)[i] = Rotate(c, s, scan.points_m[i]) + pose.head<2>();
  }
}

// The lines, residuals and noise factors of the correspondences at `pose`.
void DescribePairs(const ScanPoints& reference, const ScanPoints& current, const Pose2d& pose,
                   const std::vector<Eigen::Vector2d>& current_in_reference_m,
                   const std::vector<Correspondence>& correspondences,
                   std::vector<LinePair>* pairs) {
  const double c = std::cos(pose(2));
  const double s = std::sin(pose(2));
  pairs->resize(correspondences.size());
  for (size_t k = 0; k < correspondences.size(); ++k) {
    LinePair& pair = (*pairs)[k];
    pair.c = correspondences[k];
    const Eigen::Vector2d& qa = reference.points_m[pair.c.line_a];
    const Eigen::Vector2d& qb = reference.points_m[pair.c.line_b];
    const Eigen::Vector2d along = qb - qa;
    const double length2 = along.squaredNorm();
    pair.normal = Eigen::Vector2d(-along.y(), along.x()) / std::sqrt(length2);
    const Eigen::Vector2d d = current_in_reference_m[pair.c.current] - qa;
    pair.alpha = d.dot(along) / length2;
    pair.residual_m = pair.normal.dot(d);
    const double dp = pair.normal.dot(Rotate(c, s, current.directions[pair.c.current]));
    const double da = (1.0 - pair.alpha) * pair.normal.dot(reference.directions[pair.c.line_a]);
    const double db = pair.alpha * pair.normal.dot(reference.directions[pair.c.line_b]);
    pair.variance_factor = std::max(dp * dp + da * da + db * db, 1e-6);
    pair.inlier = true;
  }
}

// σ̂ = 1.4826·median(|rᵢ|/√vᵢ): the range noise the residuals imply, robust to outliers.
double RobustRangeSigma(const std::vector<LinePair>& pairs, std::vector<double>* scratch) {
  if (pairs.empty()) return 0.0;
  scratch->clear();
  for (const LinePair& p : pairs)
    scratch->push_back(std::abs(p.residual_m) / std::sqrt(p.variance_factor));
  auto middle = scratch->begin() + scratch->size() / 2;
  std::nth_element(scratch->begin(), middle, scratch->end());
  return 1.4826 * *middle;
}

// Marks outliers beyond outlier_sigmas·σ̂, then the worst trim_fraction of the inliers.
void MarkInliers(double sigma_m, const PlIcpOptions& options, std::vector<LinePair>* pairs,
                 std::vector<double>* scratch) {
  if (std::isinf(sigma_m)) {
    for (LinePair& p : *pairs) p.inlier = true;
    return;
  }
  // Ranges come as floats: residuals below ~1 µm are rounding, never outliers.
  const double floor_m = 1e-6;
  const double threshold_m = std::max(options.outlier_sigmas * sigma_m, floor_m);
  scratch->clear();
  for (LinePair& p : *pairs) {
    p.inlier = std::abs(p.residual_m) <= threshold_m * std::sqrt(p.variance_factor);
    if (p.inlier) scratch->push_back(std::abs(p.residual_m));
  }
  const int drop = static_cast<int>(options.trim_fraction * scratch->size());
  if (drop <= 0) return;
  auto cut = scratch->end() - drop - 1;
  std::nth_element(scratch->begin(), cut, scratch->end());
  const double trim_m = *cut;
  for (LinePair& p : *pairs) p.inlier = p.inlier && std::abs(p.residual_m) <= trim_m;
}

// Gauss–Newton normal equations of Σ rᵢ² over the inliers at `pose`:
// ∂r/∂(x, y, θ) = (nₓ, n_y, n·(R p)^⊥) with (R p)^⊥ = (−(R p)_y, (R p)_x).
struct NormalEquations {
  Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
  double cost = 0.0;
  int count = 0;
};

Eigen::Vector3d ResidualJacobian(const LinePair& pair, const Eigen::Vector2d& rotated_point) {
  return {pair.normal.x(), pair.normal.y(),
          pair.normal.dot(Eigen::Vector2d(-rotated_point.y(), rotated_point.x()))};
}

NormalEquations Linearize(const ScanPoints& reference, const ScanPoints& current,
                          const Pose2d& pose, const std::vector<LinePair>& pairs) {
  const double c = std::cos(pose(2));
  const double s = std::sin(pose(2));
  NormalEquations eq;
  for (const LinePair& pair : pairs) {
    if (!pair.inlier) continue;
    const Eigen::Vector2d rp = Rotate(c, s, current.points_m[pair.c.current]);
    const double r = pair.normal.dot(rp + pose.head<2>() - reference.points_m[pair.c.line_a]);
    const Eigen::Vector3d j = ResidualJacobian(pair, rp);
    eq.hessian += j * j.transpose();
    eq.gradient += j * r;
    eq.cost += r * r;
    ++eq.count;
  }
  return eq;
}

// J(θ) = zᵀ S z with z = (cos θ, sin θ, 1) and its first two derivatives in θ.
Eigen::Vector3d ReducedCost(const Eigen::Matrix3d& s, double theta) {
  const double c = std::cos(theta);
  const double n = std::sin(theta);
  const double cost = s(0, 0) * c * c + 2 * s(0, 1) * c * n + s(1, 1) * n * n + 2 * s(0, 2) * c +
                      2 * s(1, 2) * n + s(2, 2);
  const double d1 = 2 * (s(1, 1) - s(0, 0)) * c * n + 2 * s(0, 1) * (c * c - n * n) -
                    2 * s(0, 2) * n + 2 * s(1, 2) * c;
  const double d2 = 2 * (s(1, 1) - s(0, 0)) * (c * c - n * n) - 8 * s(0, 1) * c * n -
                    2 * s(0, 2) * c - 2 * s(1, 2) * n;
  return {cost, d1, d2};
}

// The exact minimiser of Σ rᵢ² over the inliers with the lines fixed (the closed form of the
// paper, reached by a 1-D Newton search instead of its quartic). With the rotation (c, s) and the
// translation step δt, rᵢ = c·(nᵢ·pᵢ) + s·(nᵢ×pᵢ) + nᵢ·δt − nᵢ·(qᵢ − t₀) is linear in
// u = (c, s, 1, δt), so Σ rᵢ² = uᵀMu; eliminating δt leaves zᵀSz in z = (c, s, 1). A tiny damping
// on δt keeps an unconstrained direction (a corridor's axis) where the guess put it.
struct FixedPairsSolution {
  Pose2d pose = Pose2d::Zero();
  // At the starting pose: H = Σ JᵢJᵢᵀ in (x, y, θ) and the mean squared residual, so that
  // σ²H⁻¹ approximates the pose's covariance.
  Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
  double mean_square_m2 = 0.0;
};

FixedPairsSolution SolveFixedPairs(const ScanPoints& reference, const ScanPoints& current,
                                   const Pose2d& pose, const std::vector<LinePair>& pairs) {
  FixedPairsSolution out;
  out.pose = pose;
  Eigen::Matrix<double, 5, 5> m = Eigen::Matrix<double, 5, 5>::Zero();
  int count = 0;
  for (const LinePair& pair : pairs) {
    if (!pair.inlier) continue;
    const Eigen::Vector2d& p = current.points_m[pair.c.current];
    const Eigen::Vector2d& n = pair.normal;
    Eigen::Matrix<double, 5, 1> v;
    v << n.dot(p), n.y() * p.x() - n.x() * p.y(),
        -n.dot(reference.points_m[pair.c.line_a] - pose.head<2>()), n.x(), n.y();
    m.noalias() += v * v.transpose();
    ++count;
  }
  if (count < 3) return out;
  // ∂u/∂(x, y, θ) at the starting pose: H = AᵀMA, and Σ rᵢ² = u₀ᵀMu₀.
  const double c0 = std::cos(pose(2));
  const double s0 = std::sin(pose(2));
  Eigen::Matrix<double, 5, 3> a = Eigen::Matrix<double, 5, 3>::Zero();
  a(3, 0) = a(4, 1) = 1.0;
  a(0, 2) = -s0;
  a(1, 2) = c0;
  out.hessian = a.transpose() * m * a;
  const Eigen::Matrix<double, 5, 1> u0 =
      (Eigen::Matrix<double, 5, 1>() << c0, s0, 1, 0, 0).finished();
  out.mean_square_m2 = u0.dot(m * u0) / count;
  Eigen::Matrix2d mtt = m.bottomRightCorner<2, 2>();
  mtt += (1e-9 * mtt.trace() + 1e-300) * Eigen::Matrix2d::Identity();
  const Eigen::Matrix<double, 2, 3> mtz = m.bottomLeftCorner<2, 3>();
  const Eigen::Matrix<double, 2, 3> t_of_z = -mtt.ldlt().solve(mtz);  // δt = t_of_z · z.
  const Eigen::Matrix3d s = m.topLeftCorner<3, 3>() + mtz.transpose() * t_of_z;
  double theta = pose(2);
  for (int step = 0; step < 30; ++step) {
    const Eigen::Vector3d j = ReducedCost(s, theta);
    // Newton where the cost is convex, else a bounded descent step; halved until it descends.
    double delta = j(2) > 0 ? -j(1) / j(2) : (j(1) > 0 ? -0.05 : 0.05);
    delta = std::clamp(delta, -0.3, 0.3);
    while (std::abs(delta) > 1e-16 &&
           ReducedCost(s, theta + delta)(0) > j(0) + 1e-15 * std::abs(j(0))) {
      delta *= 0.5;
    }
    theta += delta;
    if (std::abs(delta) < 1e-15) break;
  }
  const Eigen::Vector3d z(std::cos(theta), std::sin(theta), 1.0);
  const Eigen::Vector2d t = pose.head<2>() + t_of_z * z;
  if (t.allFinite() && std::isfinite(theta)) out.pose = Pose2d(t.x(), t.y(), theta);
  return out;
}

// H⁻¹ with eigenvalues floored, so that a degenerate H gives a huge but finite covariance.
Eigen::Matrix3d SafeInverse(const Eigen::Matrix3d& h) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(h);
  const Eigen::Vector3d values = eig.eigenvalues();
  const double floor = std::max(values.maxCoeff() * 1e-15, 1e-300);
  const Eigen::Vector3d inverse = values.cwiseMax(floor).cwiseInverse();
  return eig.eigenvectors() * inverse.asDiagonal() * eig.eigenvectors().transpose();
}

// Censi's closed-form covariance: Σ = H⁻¹ M H⁻¹ σ̂², M = Σₖ gₖgₖᵀ, gₖ = Σᵢ Jᵢ ∂rᵢ/∂zₖ over the
// ranges zₖ of the current points and of the reference points (shared by neighbouring lines).
Eigen::Matrix3d CensiCovariance(const ScanPoints& reference, const ScanPoints& current,
                                const Pose2d& pose, const std::vector<LinePair>& pairs,
                                const Eigen::Matrix3d& hessian, double sigma_m) {
  const double c = std::cos(pose(2));
  const double s = std::sin(pose(2));
  std::vector<Eigen::Vector3d> reference_g(reference.points_m.size(), Eigen::Vector3d::Zero());
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  for (const LinePair& pair : pairs) {
    if (!pair.inlier) continue;
    const Eigen::Vector3d j =
        ResidualJacobian(pair, Rotate(c, s, current.points_m[pair.c.current]));
    const double d_current = pair.normal.dot(Rotate(c, s, current.directions[pair.c.current]));
    m += (j * d_current) * (j * d_current).transpose();
    reference_g[pair.c.line_a] -=
        j * ((1.0 - pair.alpha) * pair.normal.dot(reference.directions[pair.c.line_a]));
    reference_g[pair.c.line_b] -=
        j * (pair.alpha * pair.normal.dot(reference.directions[pair.c.line_b]));
  }
  for (const Eigen::Vector3d& g : reference_g) m += g * g.transpose();
  const Eigen::Matrix3d h_inverse = SafeInverse(hessian);
  return sigma_m * sigma_m * h_inverse * m * h_inverse;
}

// Σ E[J r] over the inlier pairs (line_noise_bias.h).
Eigen::Vector3d NoiseGradientBias(const ScanPoints& reference, const ScanPoints& current,
                                  const Pose2d& pose, const std::vector<LinePair>& pairs,
                                  double sigma_m) {
  const double c = std::cos(pose(2));
  const double s = std::sin(pose(2));
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();
  for (const LinePair& pair : pairs) {
    if (!pair.inlier) continue;
    bias += LineNoiseGradientBias(
        reference.points_m[pair.c.line_a], reference.points_m[pair.c.line_b],
        reference.directions[pair.c.line_a], reference.directions[pair.c.line_b], pair.alpha,
        Rotate(c, s, current.points_m[pair.c.current]),
        Rotate(c, s, current.directions[pair.c.current]), sigma_m);
  }
  return bias;
}

// λmin/λmax of S H S with S = diag(1, 1, 1/L), L the inliers' RMS range, so that a rotation
// counts as the displacement it causes at the points.
double InformationRatio(const ScanPoints& current, const std::vector<LinePair>& pairs,
                        const Eigen::Matrix3d& hessian) {
  double sum2 = 0.0;
  int n = 0;
  for (const LinePair& pair : pairs) {
    if (!pair.inlier) continue;
    sum2 += current.points_m[pair.c.current].squaredNorm();
    ++n;
  }
  if (n == 0) return 0.0;
  const double length_m = std::max(std::sqrt(sum2 / n), 1e-6);
  const Eigen::Vector3d scale(1.0, 1.0, 1.0 / length_m);
  const Eigen::Matrix3d scaled = scale.asDiagonal() * hessian * scale.asDiagonal();
  const Eigen::Vector3d values =
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scaled).eigenvalues();
  return values.maxCoeff() > 0.0 ? std::max(values.minCoeff(), 0.0) / values.maxCoeff() : 0.0;
}

// A fingerprint of the correspondences and their inlier flags (FNV-1a).
uint64_t PairsHash(const std::vector<LinePair>& pairs) {
  uint64_t h = 1469598103934665603ull;
  auto mix = [&h](uint64_t v) { h = (h ^ v) * 1099511628211ull; };
  for (const LinePair& p : pairs) {
    mix(static_cast<uint64_t>(p.c.current) << 1 | (p.inlier ? 1 : 0));
    mix(static_cast<uint64_t>(p.c.reference_a) << 32 | static_cast<uint32_t>(p.c.reference_b));
  }
  return h;
}

Status CheckOptions(const PlIcpOptions& o) {
  const bool ok = o.correspondence.max_distance_m > 0 &&
                  o.correspondence.max_segment_length_m > 0 &&
                  o.correspondence.scan_end_beams >= 0 && o.max_iterations > 0 &&
                  o.outlier_sigmas > 0 && o.trim_fraction >= 0 && o.trim_fraction < 1 &&
                  o.min_correspondences >= 3 && std::isfinite(o.max_rms_residual_m) &&
                  std::isfinite(o.min_information_ratio) && std::isfinite(o.step_tolerance_m) &&
                  std::isfinite(o.step_tolerance_rad) && std::isfinite(o.step_tolerance_sigmas) &&
                  o.step_tolerance_sigmas >= 0 && o.coarse_points >= 0;
  return ok ? Status::Ok()
            : Status::InvalidInput(
                  "PL-ICP options: distances and outlier_sigmas must be positive, trim_fraction "
                  "in [0, 1), max_iterations ≥ 1, min_correspondences ≥ 3, all finite");
}

ScanMatch Unmatched(const Pose2d& guess, int matched, int needed, int returns) {
  ScanMatch m;
  m.reference_T_current = guess;
  const double inf = std::numeric_limits<double>::infinity();
  m.covariance = Eigen::Vector3d(inf, inf, inf).asDiagonal();
  m.correspondences = matched;
  m.quality = ScanMatchQuality::kTooFewCorrespondences;
  m.reason = "only " + std::to_string(matched) + " of the current scan's " +
             std::to_string(returns) + " returns matched the reference (" + std::to_string(needed) +
             " needed)";
  return m;
}

void Judge(const PlIcpOptions& options, ScanMatch* m) {
  char buffer[200];
  if (m->information_ratio < options.min_information_ratio) {
    m->quality = ScanMatchQuality::kDegenerate;
    std::snprintf(buffer, sizeof(buffer),
                  "the geometry constrains its weakest direction %.3g times less than its "
                  "strongest (below %.3g), as along a featureless corridor",
                  m->information_ratio, options.min_information_ratio);
  } else if (!m->converged) {
    m->quality = ScanMatchQuality::kNotConverged;
    std::snprintf(buffer, sizeof(buffer), "the correspondences still changed after %d iterations",
                  m->iterations);
  } else if (m->rms_residual_m > options.max_rms_residual_m) {
    m->quality = ScanMatchQuality::kLargeResidual;
    std::snprintf(buffer, sizeof(buffer), "the RMS point-to-line residual %.3g m exceeds %.3g m",
                  m->rms_residual_m, options.max_rms_residual_m);
  } else {
    m->quality = ScanMatchQuality::kOk;
    buffer[0] = '\0';
  }
  m->reason = buffer;
}

}  // namespace

const char* ScanMatchQualityName(ScanMatchQuality quality) {
  switch (quality) {
    case ScanMatchQuality::kOk:
      return "ok";
    case ScanMatchQuality::kTooFewCorrespondences:
      return "too few correspondences";
    case ScanMatchQuality::kDegenerate:
      return "degenerate geometry";
    case ScanMatchQuality::kLargeResidual:
      return "large residual";
    case ScanMatchQuality::kNotConverged:
      return "did not converge";
  }
  return "unknown";
}

StatusOr<ScanMatch> MatchScanPoints(const ScanPoints& reference, const ScanPoints& current,
                                    const Pose2d& reference_T_current_guess,
                                    const PlIcpOptions& options) {
  if (!reference_T_current_guess.allFinite()) {
    return Status::InvalidInput("PL-ICP: the guess reference_T_current is not finite");
  }
  CALIB_RETURN_IF_ERROR(CheckOptions(options));
  const int returns = current.NumPoints();
  const int needed = std::max(options.min_correspondences,
                              static_cast<int>(std::ceil(options.min_matched_fraction * returns)));
  if (returns < needed || reference.NumPoints() < 2) {
    return Unmatched(reference_T_current_guess, 0, needed, returns);
  }
  Pose2d pose = reference_T_current_guess;
  pose(2) = WrapAngle(pose(2));
  std::vector<Eigen::Vector2d> moved;
  std::vector<Correspondence> correspondences;
  std::vector<LinePair> pairs;
  const double kNoRejection = std::numeric_limits<double>::infinity();
  bool settled = false;
  std::array<uint64_t, 16> recent_hashes;
  recent_hashes.fill(0);
  std::vector<double> scratch;
  const CorrespondenceSearch search(reference, options.correspondence);
  // Coarse to fine: far from the solution the points pull the pose alike, so until it settles
  // the iterations use every stride-th point only (about coarse_points of them).
  int stride =
      options.coarse_points > 0
          ? std::max(1, static_cast<int>(std::lround(1.0 * returns / options.coarse_points)))
          : 1;
  const auto go_fine = [&] {
    stride = 1;
    settled = true;  // Within settle_step of the solution: outliers can be told now.
    recent_hashes.fill(0);
  };
  ScanMatch m;
  bool pairs_at_pose = false;
  for (m.iterations = 1; m.iterations <= options.max_iterations; ++m.iterations) {
    TransformPoints(current, pose, &moved);
    search.Find(moved, stride, &correspondences);
    DescribePairs(reference, current, pose, moved, correspondences, &pairs);
    MarkInliers(settled ? RobustRangeSigma(pairs, &scratch) : kNoRejection, options, &pairs,
                &scratch);
    // Converged when the correspondences repeat: the same set as the last solve, or a short
    // cycle (points flickering across the outlier threshold), whose poses differ negligibly.
    uint64_t hash = PairsHash(pairs);
    const auto repeats = [&] {
      return std::find(recent_hashes.begin(), recent_hashes.end(), hash) != recent_hashes.end();
    };
    if (repeats() && stride > 1) {
      go_fine();  // The subsample converged: on with every point from the same pose.
      continue;
    }
    if (repeats() && !settled) {
      // Converged with every pair: now drop the outliers and go on.
      settled = true;
      MarkInliers(RobustRangeSigma(pairs, &scratch), options, &pairs, &scratch);
      hash = PairsHash(pairs);
    }
    if (repeats()) {
      m.converged = true;
      pairs_at_pose = true;
      break;
    }
    recent_hashes[m.iterations % recent_hashes.size()] = hash;
    const FixedPairsSolution solution = SolveFixedPairs(reference, current, pose, pairs);
    const Pose2d step = solution.pose - pose;
    pose = solution.pose;
    // Outliers are judged against σ̂ only once the pose has settled: far from it the residuals of
    // a whole wall direction can exceed the median and would all be dropped.
    const bool was_settled = settled;
    settled = settled || (step.head<2>().norm() < options.settle_step_m &&
                          std::abs(step(2)) < options.settle_step_rad);
    if (stride > 1) {
      if (settled) go_fine();
      continue;
    }
    // Dense scans' correspondences flicker for many iterations at a noise floor of steps far
    // below the pose's own uncertainty (σ²H⁻¹, σ² the mean squared residual): stop there too.
    const double step_sigmas2 =
        step.dot(solution.hessian * step) / std::max(solution.mean_square_m2, 1e-300);
    const bool tiny_step =
        (step.head<2>().norm() < options.step_tolerance_m &&
         std::abs(step(2)) < options.step_tolerance_rad) ||
        step_sigmas2 < options.step_tolerance_sigmas * options.step_tolerance_sigmas;
    if (was_settled && tiny_step) {
      m.converged = true;
      break;
    }
  }
  m.iterations = std::min(m.iterations, options.max_iterations);
  if (!pairs_at_pose) {  // The last solve moved the pose: the final pairs are described there.
    TransformPoints(current, pose, &moved);
    if (stride > 1) search.Find(moved, 1, &correspondences);
    DescribePairs(reference, current, pose, moved, correspondences, &pairs);
    MarkInliers(RobustRangeSigma(pairs, &scratch), options, &pairs, &scratch);
  }
  const NormalEquations eq = Linearize(reference, current, pose, pairs);
  if (eq.count < needed) return Unmatched(pose, eq.count, needed, returns);
  m.range_sigma_m = RobustRangeSigma(pairs, &scratch);
  m.covariance = CensiCovariance(reference, current, pose, pairs, eq.hessian, m.range_sigma_m);
  if (options.correct_noise_bias) {
    // A second-order correction is typically a fraction of the pose's σ (median 0.3σ on dense
    // scans, with a tail to a few σ along weak directions, which it also helps); one of over 5σ
    // is no expansion to trust (a nearly degenerate match, which is judged below anyway).
    const Eigen::Vector3d correction =
        SafeInverse(eq.hessian) *
        NoiseGradientBias(reference, current, pose, pairs, m.range_sigma_m);
    if (correction.dot(SafeInverse(m.covariance) * correction) < 25.0) pose += correction;
  }
  pose(2) = WrapAngle(pose(2));
  m.reference_T_current = pose;
  m.correspondences = eq.count;
  m.rms_residual_m = std::sqrt(eq.cost / eq.count);
  m.information_ratio = InformationRatio(current, pairs, eq.hessian);
  Judge(options, &m);
  return m;
}

StatusOr<ScanMatch> MatchScans(const LaserScan& reference, const LaserScan& current,
                               const Pose2d& reference_T_current_guess,
                               const PlIcpOptions& options) {
  CALIB_ASSIGN_OR_RETURN(ScanPoints reference_points,
                         MakeScanPoints(reference, options.reference_points));
  CALIB_ASSIGN_OR_RETURN(ScanPoints current_points,
                         MakeScanPoints(current, options.current_points));
  return MatchScanPoints(reference_points, current_points, reference_T_current_guess, options);
}

}  // namespace calib
