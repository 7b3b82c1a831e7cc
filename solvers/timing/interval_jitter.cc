#include <calib/core/order_statistic.h>
#include <calib/core/se2.h>
#include <calib/core/sin_cos.h>
#include <calib/core/whitening.h>
#include <calib/problems/laser/laser_residual.h>
#include <calib/solvers/timing/interval_jitter.h>
#include <calib/solvers/timing/interval_jitter_likelihood.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace calib {
namespace {

using jitter_internal::JitterData;
using jitter_internal::JointMaximum;
using jitter_internal::kGridTolerance;
using jitter_internal::kMinVariance;
using jitter_internal::ProfileLogLikelihood;

// A side of a boundary: the wheel speeds next to it and the duration they were averaged over.
struct SideSpeed {
  Eigen::Vector2d speed;
  double duration_s;
};

SideSpeed StartSide(const LaserInterval& interval) {
  if (interval.steps.empty() || !(interval.steps.front().duration_s > 0.0)) {
    return {Eigen::Vector2d(interval.left_speed, interval.right_speed), interval.duration_s};
  }
  const WheelStep& step = interval.steps.front();
  return {Eigen::Vector2d(step.left_rad, step.right_rad) / step.duration_s, step.duration_s};
}

SideSpeed EndSide(const LaserInterval& interval) {
  if (interval.steps.empty() || !(interval.steps.back().duration_s > 0.0)) {
    return {Eigen::Vector2d(interval.left_speed, interval.right_speed), interval.duration_s};
  }
  const WheelStep& step = interval.steps.back();
  return {Eigen::Vector2d(step.left_rad, step.right_rad) / step.duration_s, step.duration_s};
}

// Linear interpolation at the boundary between the centres of the two sides.
Eigen::Vector2d Interpolate(const SideSpeed& before, const SideSpeed& after) {
  return (after.duration_s * before.speed + before.duration_s * after.speed) /
         (before.duration_s + after.duration_s);
}

// ∂ŝ/∂ε of the sensor displacement ŝ = ℓ⁻¹∘M∘ℓ when the interval's start moves by ε_s and its
// end by ε_e, in closed form. M = (t, θ) is the robot motion; ξ = (v, ω) the twist of the wheel
// speeds at an end. The end's shift appends Exp(ε_e·ξ_e): ∂M = (R(θ)·(v_e, 0), ω_e). The start's
// prepends Exp(−ε_s·ξ_s): ∂M = (−v_s + ω_s·t_y, −ω_s·t_x, −ω_s). Through ℓ:
//   ∂ŝ_xy = R(−ℓ_θ)·[∂t + ∂θ·R'(θ)·ℓ_p],  ∂ŝ_θ = ∂θ.
IntervalTimeSensitivity ShiftSensitivity(const OdometryParams& p, const Pose2d& robot_motion,
                                         const IntervalBoundarySpeeds& speeds,
                                         const Eigen::Matrix2d& to_sensor,
                                         const Eigen::Vector2d& mount) {
  const auto twist = [&](const Eigen::Vector2d& wheel) {
    return Eigen::Vector2d(
        (p.left_radius_m * wheel(0) + p.right_radius_m * wheel(1)) / 2.0,
        (p.right_radius_m * wheel(1) - p.left_radius_m * wheel(0)) / p.wheelbase_m);
  };
  const Eigen::Vector2d xi_s = twist(speeds.start), xi_e = twist(speeds.end);
  double s, c;
  SinCos(robot_motion(2), &s, &c);
  // R'(θ)·ℓ_p: what a unit turn of M does to the mounting's offset.
  const Eigen::Vector2d turned(-s * mount(0) - c * mount(1), c * mount(0) - s * mount(1));
  const auto through_mounting = [&](const Eigen::Vector2d& dt, double dtheta) {
    Eigen::Vector3d g;
    g << to_sensor * (dt + dtheta * turned), dtheta;
    return g;
  };
  IntervalTimeSensitivity g;
  g.end = through_mounting(Eigen::Vector2d(c * xi_e(0), s * xi_e(0)), xi_e(1));
  g.start = through_mounting(
      Eigen::Vector2d(-xi_s(0) + xi_s(1) * robot_motion(1), -xi_s(1) * robot_motion(0)), -xi_s(1));
  return g;
}

// G = g_s g_sᵀ + g_e g_eᵀ, packed as (00, 01, 02, 11, 12, 22).
void PackedGram(const IntervalTimeSensitivity& g, double gram[6]) {
  const Eigen::Vector3d &s = g.start, &e = g.end;
  gram[0] = s(0) * s(0) + e(0) * e(0), gram[1] = s(0) * s(1) + e(0) * e(1);
  gram[2] = s(0) * s(2) + e(0) * e(2), gram[3] = s(1) * s(1) + e(1) * e(1);
  gram[4] = s(1) * s(2) + e(1) * e(2), gram[5] = s(2) * s(2) + e(2) * e(2);
}

// Golden-section maximum of f on [lo, hi].
template <typename F>
double GoldenMaximum(const F& f, double lo, double hi, double tolerance = 1e-6) {
  const double ratio = (std::sqrt(5.0) - 1.0) / 2.0;
  double a = hi - ratio * (hi - lo), b = lo + ratio * (hi - lo);
  double fa = f(a), fb = f(b);
  for (int i = 0; i < 60 && hi - lo > tolerance * hi; ++i) {
    if (fa < fb) {
      lo = a, a = b, fa = fb, b = lo + ratio * (hi - lo), fb = f(b);
    } else {
      hi = b, b = a, fb = fa, a = hi - ratio * (hi - lo), fa = f(a);
    }
  }
  return fa > fb ? a : b;
}

// The maximum of the profile on a grid 0, scale·10^(−2.5 … 1.5) (`value_at_zero` at 0; `rank`
// scores a grid point), refined between the best point's neighbours: by `joint` (see
// JointMaximum) when the best is not 0, else or when that fails by golden section.
template <typename F, typename R, typename J>
void SearchFromGrid(const F& profile, const R& rank, const J& joint, double scale, int grid_points,
                    double value_at_zero, double* jitter_s, double* value) {
  const int points = std::max(grid_points, 5);
  std::vector<double> grid = {0.0}, values = {value_at_zero};
  for (int i = 0; i + 1 < points; ++i) {
    grid.push_back(scale * std::pow(10.0, -2.5 + 4.0 * i / (points - 2)));
    values.push_back(rank(grid.back()));
  }
  const size_t best = std::max_element(values.begin(), values.end()) - values.begin();
  const double lo = best == 0 ? 0.0 : grid[best - 1];
  const double hi = best + 1 < grid.size() ? grid[best + 1] : grid[best] * 10.0;
  if (!(best > 0 && joint(lo, hi, grid[best], jitter_s)))
    *jitter_s = GoldenMaximum(profile, lo, hi);
  *value = profile(*jitter_s);
  if (*value < values[best]) *jitter_s = grid[best], *value = values[best];
}

// The maximum within a factor of 3 of `previous` (by `joint`, else golden section); false when it
// lies on the bracket's edge (the grid must then look further).
template <typename F, typename J>
bool NearPrevious(const F& profile, const J& joint, double previous, double* jitter_s,
                  double* value) {
  const double lo = previous / 3.0, hi = previous * 3.0;
  if (joint(lo, hi, previous, jitter_s)) {
    *value = profile(*jitter_s);
    return true;
  }
  // 10⁻⁴ of σ_j, far below its σ (a few per cent), as the refit's rounds need.
  *jitter_s = GoldenMaximum(profile, lo, hi, 1e-4);
  *value = profile(*jitter_s);
  return *jitter_s > 1.01 * lo && *jitter_s < 0.99 * hi;
}

// σ of σ_j at the maximum (σ_j, value). With the joint scoring's observed information there in
// (θ, σ_j²): σ_j² by that information (the profile's curvature in σ_j² is the Schur complement of
// θ's block), σ_j = √σ_j² by the delta method. Else from the profile's curvature by differences
// (ℓ is even in σ_j, so at 0 the one-sided difference).
template <typename F>
double JitterStddev(const F& profile, double jitter_s, double value, double scale,
                    const Eigen::Matrix4d* information) {
  if (information != nullptr && jitter_s > 0.0) {
    const Eigen::LDLT<Eigen::Matrix4d> ldlt(*information);
    if (ldlt.info() == Eigen::Success && (ldlt.vectorD().array() > 0.0).all()) {
      return std::sqrt(ldlt.solve(Eigen::Vector4d::UnitW())(3)) / (2.0 * jitter_s);
    }
  }
  const double h = std::max(0.1 * jitter_s, 0.01 * scale);
  const double curvature =
      jitter_s > h ? (profile(jitter_s + h) - 2.0 * value + profile(jitter_s - h)) / (h * h)
                   : 2.0 * (profile(jitter_s + h) - profile(jitter_s)) / (h * h);
  return curvature < 0.0 ? 1.0 / std::sqrt(-curvature) : std::numeric_limits<double>::infinity();
}

}  // namespace

std::vector<IntervalBoundarySpeeds> BoundaryWheelSpeeds(
    const std::vector<LaserInterval>& intervals) {
  std::vector<IntervalBoundarySpeeds> speeds(intervals.size());
  for (size_t k = 0; k < intervals.size(); ++k) {
    speeds[k].start = StartSide(intervals[k]).speed;
    speeds[k].end = EndSide(intervals[k]).speed;
  }
  for (size_t k = 1; k < intervals.size(); ++k) {
    if (intervals[k].gap_before) continue;
    const Eigen::Vector2d shared = Interpolate(EndSide(intervals[k - 1]), StartSide(intervals[k]));
    speeds[k - 1].end = shared;
    speeds[k].start = shared;
  }
  return speeds;
}

std::vector<IntervalTimeSensitivity> IntervalTimeSensitivities(
    const std::vector<LaserInterval>& intervals, const LaserCalibration& calibration) {
  return IntervalTimeSensitivities(intervals, BoundaryWheelSpeeds(intervals), calibration);
}

namespace {

// BoundaryWheelSpeeds(intervals)[k] alone: a sample of a long log needs only its own.
IntervalBoundarySpeeds BoundaryWheelSpeedsOf(const std::vector<LaserInterval>& intervals,
                                             size_t k) {
  IntervalBoundarySpeeds at;
  at.start = k > 0 && !intervals[k].gap_before
                 ? Interpolate(EndSide(intervals[k - 1]), StartSide(intervals[k]))
                 : StartSide(intervals[k]).speed;
  at.end = k + 1 < intervals.size() && !intervals[k + 1].gap_before
               ? Interpolate(EndSide(intervals[k]), StartSide(intervals[k + 1]))
               : EndSide(intervals[k]).speed;
  return at;
}

// The sensitivities of the intervals at indices[i] (all when `indices` is null), speeds_of(k)
// giving interval k's boundary speeds.
template <typename SpeedsOf>
std::vector<IntervalTimeSensitivity> SensitivitiesAt(const std::vector<LaserInterval>& intervals,
                                                     const SpeedsOf& speeds_of,
                                                     const LaserCalibration& calibration,
                                                     const std::vector<size_t>* indices) {
  const OdometryParams& p = calibration.odometry;
  const Pose2d& mounting = calibration.base_T_sensor;
  const double cl = std::cos(mounting(2)), sl = std::sin(mounting(2));
  const Eigen::Matrix2d to_sensor = (Eigen::Matrix2d() << cl, sl, -sl, cl).finished();
  const Eigen::Vector2d mount(mounting(0), mounting(1));
  std::vector<IntervalTimeSensitivity> sensitivities(indices ? indices->size() : intervals.size());
  for (size_t i = 0; i < sensitivities.size(); ++i) {
    const size_t k = indices ? (*indices)[i] : i;
    const Pose2d robot_motion =
        IntervalRobotMotion(p.left_radius_m, p.right_radius_m, p.wheelbase_m, intervals[k]);
    sensitivities[i] = ShiftSensitivity(p, robot_motion, speeds_of(k), to_sensor, mount);
  }
  return sensitivities;
}

}  // namespace

std::vector<IntervalTimeSensitivity> IntervalTimeSensitivities(
    const std::vector<LaserInterval>& intervals, const LaserCalibration& calibration,
    const std::vector<size_t>& indices) {
  return SensitivitiesAt(
      intervals, [&](size_t k) { return BoundaryWheelSpeedsOf(intervals, k); }, calibration,
      &indices);
}

std::vector<IntervalTimeSensitivity> IntervalTimeSensitivities(
    const std::vector<LaserInterval>& intervals, const std::vector<IntervalBoundarySpeeds>& speeds,
    const LaserCalibration& calibration) {
  return SensitivitiesAt(
      intervals, [&](size_t k) -> const IntervalBoundarySpeeds& { return speeds[k]; }, calibration,
      nullptr);
}

Eigen::Matrix3d JitterCovariance(const IntervalTimeSensitivity& g, double jitter_s) {
  return jitter_s * jitter_s * (g.start * g.start.transpose() + g.end * g.end.transpose());
}

std::vector<Eigen::Matrix3d> JitterCrossCovariances(
    const std::vector<LaserInterval>& intervals,
    const std::vector<IntervalTimeSensitivity>& sensitivities, double jitter_s) {
  std::vector<Eigen::Matrix3d> cross;
  for (size_t k = 0; k + 1 < sensitivities.size(); ++k) {
    cross.push_back(intervals[k + 1].gap_before
                        ? Eigen::Matrix3d::Zero()
                        : Eigen::Matrix3d(jitter_s * jitter_s * sensitivities[k].end *
                                          sensitivities[k + 1].start.transpose()));
  }
  return cross;
}

std::vector<Eigen::Matrix2d> JitterIncrementCovariances(const std::vector<LaserInterval>& intervals,
                                                        double jitter_s) {
  return JitterIncrementCovariances(BoundaryWheelSpeeds(intervals), jitter_s);
}

std::vector<Eigen::Matrix2d> JitterIncrementCovariances(
    const std::vector<IntervalBoundarySpeeds>& speeds, double jitter_s) {
  std::vector<Eigen::Matrix2d> covariances;
  covariances.reserve(speeds.size());
  for (const IntervalBoundarySpeeds& at : speeds) {
    covariances.push_back(jitter_s * jitter_s *
                          (at.start * at.start.transpose() + at.end * at.end.transpose()));
  }
  return covariances;
}

std::vector<Eigen::Matrix3d> JitterSqrtInformation(
    const std::vector<IntervalTimeSensitivity>& sensitivities, const Eigen::Vector3d& noise_sigma,
    double jitter_s) {
  std::vector<Eigen::Matrix3d> roots;
  roots.reserve(sensitivities.size());
  const Eigen::Matrix3d noise = noise_sigma.cwiseAbs2().asDiagonal();
  for (const IntervalTimeSensitivity& g : sensitivities) {
    roots.push_back(SqrtInformation<3>(noise + JitterCovariance(g, jitter_s)));
  }
  return roots;
}

std::vector<double> JitterWhitenedSquaredNorms(
    const std::vector<Eigen::Vector3d>& errors,
    const std::vector<IntervalTimeSensitivity>& sensitivities, const Eigen::Vector3d& noise_sigma,
    double jitter_s) {
  const size_t n = std::min(errors.size(), sensitivities.size());
  std::vector<double> norms(n);
  const Eigen::Vector3d theta = noise_sigma.cwiseAbs2();
  for (size_t k = 0; k < n; ++k) {
    double gram[6], sigma[6], inverse[6], w[3];
    PackedGram(sensitivities[k], gram);
    jitter_internal::PackedCovariance(theta, jitter_s * jitter_s, gram, sigma);
    const double* error = errors[k].data();
    if (jitter_internal::InverseOfSymmetric(sigma, inverse) > 0.0) {
      jitter_internal::MultiplySymmetric(inverse, error, w);
      norms[k] = error[0] * w[0] + error[1] * w[1] + error[2] * w[2];
    } else {  // Not numerically positive definite: as the root does it.
      norms[k] = (SqrtInformation<3>(theta.asDiagonal().toDenseMatrix() +
                                     JitterCovariance(sensitivities[k], jitter_s)) *
                  errors[k])
                     .squaredNorm();
    }
  }
  return norms;
}

std::vector<size_t> JitterSampleIndices(size_t n, const std::vector<bool>& is_inlier,
                                        int max_intervals) {
  size_t inliers = 0;
  for (size_t k = 0; k < n; ++k) inliers += k >= is_inlier.size() || is_inlier[k];
  const size_t limit = static_cast<size_t>(std::max(max_intervals, 100));
  const size_t stride = std::max<size_t>((inliers + limit - 1) / limit, 1);
  std::vector<size_t> indices;
  size_t seen = 0;
  for (size_t k = 0; k < n; ++k) {
    if (k < is_inlier.size() && !is_inlier[k]) continue;
    if (seen++ % stride == 0) indices.push_back(k);
  }
  return indices;
}

IntervalJitterEstimate EstimateIntervalJitter(
    const std::vector<Eigen::Vector3d>& errors,
    const std::vector<IntervalTimeSensitivity>& sensitivities, const Eigen::Vector3d& noise_sigma,
    const std::vector<bool>& is_inlier, const IntervalJitterOptions& options) {
  JitterData data;
  const size_t n = std::min(errors.size(), sensitivities.size());
  const std::vector<size_t> sample = JitterSampleIndices(n, is_inlier, options.max_intervals);
  data.Reserve(sample.size());
  for (size_t k : sample) {
    double gram[6];
    PackedGram(sensitivities[k], gram);
    data.Add(errors[k].data(), gram);
  }
  IntervalJitterEstimate estimate;
  estimate.intervals_used = static_cast<int>(data.size());
  Eigen::Vector3d theta = noise_sigma.cwiseAbs2().cwiseMax(kMinVariance);
  estimate.log_likelihood_without_jitter =
      ProfileLogLikelihood(data, 0.0, options.estimate_noise, &theta);
  estimate.noise_sigma_without_jitter = estimate.noise_sigma = theta.cwiseSqrt();
  estimate.log_likelihood = estimate.log_likelihood_without_jitter;
  // The jitter that doubles a typical interval's variance sets the grid's scale.
  std::vector<double> relative;
  relative.reserve(data.size());
  for (size_t k = 0; k < data.size(); ++k) {
    relative.push_back(data.gram[0][k] / theta(0) + data.gram[3][k] / theta(1) +
                       data.gram[5][k] / theta(2));
  }
  if (relative.size() < 2) return estimate;
  const double median = UpperMedian(&relative);
  if (!(median > 0.0) || !std::isfinite(median)) return estimate;
  const double scale = 1.0 / std::sqrt(median);

  // Each evaluation starts the scoring where the previous one ended (nearby σ_j: a few steps).
  Eigen::Vector3d warm = theta;
  double warm_at = -1.0;  // The σ_j whose profiled θ `warm` holds (to full tolerance), if any.
  const auto profile = [&](double jitter_s) {
    warm_at = jitter_s;
    return ProfileLogLikelihood(data, jitter_s, options.estimate_noise, &warm);
  };
  const auto rank = [&](double jitter_s) {
    warm_at = -1.0;
    return ProfileLogLikelihood(data, jitter_s, options.estimate_noise, &warm, kGridTolerance);
  };
  // Joint scoring from σ_j = start, with θ profiled there first (the grid's warm θ belongs to
  // its last point). Its observed information at the maximum gives σ of σ_j below.
  Eigen::Matrix4d joint_information = Eigen::Matrix4d::Zero();
  double joint_at = -1.0;
  const auto joint = [&](double lo, double hi, double start, double* jitter_s) {
    if (!options.estimate_noise || !options.joint_scoring) return false;
    Eigen::Vector3d start_theta = warm;
    if (start == options.previous_jitter_s && (options.previous_noise_sigma.array() > 0.0).all()) {
      start_theta = options.previous_noise_sigma.cwiseAbs2().cwiseMax(kMinVariance);
    } else {
      ProfileLogLikelihood(data, start, true, &start_theta, kGridTolerance);
    }
    double found = start;
    if (!JointMaximum(data, lo, hi, &start_theta, &found, &joint_information)) return false;
    warm = start_theta, warm_at = -1.0;
    *jitter_s = joint_at = found;
    return true;
  };
  // Without a nearby estimate, the moments' σ_j starts the search when clearly positive (the
  // grid runs when the maximum is not within a factor of 3 of it).
  double previous = options.previous_jitter_s;
  if (!(previous > 0.0) && options.estimate_noise && options.joint_scoring) {
    previous = MomentJitter(data);
  }
  double jitter_s = 0.0, value = 0.0;
  if (!(previous > 0.0) || !NearPrevious(profile, joint, previous, &jitter_s, &value)) {
    warm = theta, warm_at = -1.0;
    SearchFromGrid(profile, rank, joint, scale, options.grid_points,
                   estimate.log_likelihood_without_jitter, &jitter_s, &value);
  }
  // θ at the chosen σ_j: `warm` already, unless the search ended on a grid point.
  Eigen::Vector3d theta_best = warm;
  if (warm_at != jitter_s) {
    ProfileLogLikelihood(data, jitter_s, options.estimate_noise, &theta_best);
  }

  estimate.jitter_s = jitter_s;
  estimate.noise_sigma = theta_best.cwiseSqrt();
  estimate.log_likelihood = value;
  estimate.lr_statistic = std::max(0.0, 2.0 * (value - estimate.log_likelihood_without_jitter));
  // On the boundary σ_j = 0 the statistic is ½χ²₀ + ½χ²₁.
  estimate.p_value =
      estimate.lr_statistic > 0.0 ? 0.5 * std::erfc(std::sqrt(estimate.lr_statistic / 2.0)) : 1.0;
  estimate.significant = estimate.p_value < options.significance;
  if (options.stddev_wanted && !options.stddev_wanted(estimate)) {
    estimate.jitter_stddev_s = std::numeric_limits<double>::quiet_NaN();
    return estimate;
  }
  estimate.jitter_stddev_s = JitterStddev(profile, jitter_s, value, scale,
                                          joint_at == jitter_s ? &joint_information : nullptr);
  return estimate;
}

IntervalJitterEstimate EstimateIntervalJitter(const std::vector<LaserInterval>& intervals,
                                              const LaserCalibration& calibration,
                                              const Eigen::Vector3d& noise_sigma,
                                              const std::vector<bool>& is_inlier,
                                              const IntervalJitterOptions& options,
                                              const std::vector<Eigen::Vector3d>* errors) {
  // Errors and sensitivities of the sampled intervals only (a million-interval log samples 2 %).
  const std::vector<size_t> sample =
      JitterSampleIndices(intervals.size(), is_inlier, options.max_intervals);
  const LaserParamVector p = calibration.ToVector();
  const SensorMounting mounting(p.data() + 3);
  const bool given = errors != nullptr && errors->size() == intervals.size();
  std::vector<Eigen::Vector3d> sampled;
  sampled.reserve(sample.size());
  for (size_t k : sample) {
    sampled.push_back(given ? (*errors)[k]
                            : LaserResidual::Error(intervals[k], p.data(), mounting));
  }
  IntervalJitterOptions all = options;
  all.max_intervals = std::max<int>(options.max_intervals, static_cast<int>(sample.size()));
  return EstimateIntervalJitter(sampled, IntervalTimeSensitivities(intervals, calibration, sample),
                                noise_sigma, {}, all);
}

std::string IntervalJitterStatement(const IntervalJitterEstimate& estimate) {
  char buffer[320];
  std::snprintf(buffer, sizeof(buffer),
                "the interval stamps scatter about the sample times (σ = %.1f ± %.1f ms): the "
                "scatter was propagated into each interval's covariance through its end speeds; "
                "only this weaker treatment was possible (it works on the intervals, without the "
                "raw odometry a latent-time calibration needs)",
                estimate.jitter_s * 1e3, estimate.jitter_stddev_s * 1e3);
  return buffer;
}

}  // namespace calib
