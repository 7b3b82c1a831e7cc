#include <calib/core/se2.h>
#include <calib/core/whitening.h>
#include <calib/problems/laser/laser_residual.h>
#include <calib/solvers/timing/interval_jitter.h>
#include <ceres/jet.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>

namespace calib {
namespace {

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

// The sensor displacement with the interval's start moved by ε_s and its end by ε_e.
template <typename T>
Eigen::Matrix<T, 3, 1> ShiftedSensorMotion(const LaserCalibration& c, const Pose2d& robot_motion,
                                           const IntervalBoundarySpeeds& speeds, const T& eps_s,
                                           const T& eps_e) {
  const OdometryParams& p = c.odometry;
  const T rl(p.left_radius_m), rr(p.right_radius_m), b(p.wheelbase_m);
  const Pose2<T> before =
      WheelStepDisplacement(rl, rr, b, T(-speeds.start(0)) * eps_s, T(-speeds.start(1)) * eps_s);
  const Pose2<T> after =
      WheelStepDisplacement(rl, rr, b, T(speeds.end(0)) * eps_e, T(speeds.end(1)) * eps_e);
  const Pose2<T> robot = Compose(Compose(before, robot_motion.cast<T>().eval()), after);
  return SensorMotionFromRobotMotion(c.base_T_sensor.cast<T>().eval(), robot);
}

// Σ_k = diag(θ) + σ_j²·G_k over the inliers, and the profile likelihood's pieces. Symmetric
// 3×3 matrices are packed as (00, 01, 02, 11, 12, 22).
struct JitterTerm {
  double error[3];
  double gram[6];  // G_k = g_s g_sᵀ + g_e g_eᵀ.
};
struct JitterData {
  std::vector<JitterTerm> terms;
};

// Σ = diag(θ) + s·G, packed.
inline void Covariance(const Eigen::Vector3d& theta, double s, const double g[6], double m[6]) {
  m[0] = theta(0) + s * g[0], m[1] = s * g[1], m[2] = s * g[2];
  m[3] = theta(1) + s * g[3], m[4] = s * g[4], m[5] = theta(2) + s * g[5];
}

// The inverse of a packed symmetric 3×3 matrix by cofactors; returns the determinant (the
// inverse is meaningless unless it is > 0).
inline double InverseOfSymmetric(const double m[6], double inverse[6]) {
  const double c00 = m[3] * m[5] - m[4] * m[4], c01 = m[2] * m[4] - m[1] * m[5],
               c02 = m[1] * m[4] - m[2] * m[3];
  const double det = m[0] * c00 + m[1] * c01 + m[2] * c02;
  const double r = 1.0 / det;
  inverse[0] = c00 * r, inverse[1] = c01 * r, inverse[2] = c02 * r;
  inverse[3] = (m[0] * m[5] - m[2] * m[2]) * r;
  inverse[4] = (m[1] * m[2] - m[0] * m[4]) * r;
  inverse[5] = (m[0] * m[3] - m[1] * m[1]) * r;
  return det;
}

// y = M·x for a packed symmetric M.
inline void MultiplySymmetric(const double m[6], const double x[3], double y[3]) {
  y[0] = m[0] * x[0] + m[1] * x[1] + m[2] * x[2];
  y[1] = m[1] * x[0] + m[3] * x[1] + m[4] * x[2];
  y[2] = m[2] * x[0] + m[4] * x[1] + m[5] * x[2];
}

// Σ log x_k over positive x without a logarithm per term: binary exponents summed as integers,
// mantissas (in [1, 2)) multiplied and folded back every 32 terms.
class LogSum {
 public:
  void Add(double x) {
    if (!(x >= std::numeric_limits<double>::min()) || !(x < kInfinity)) {
      plain_ += std::log(x);
      return;
    }
    uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    exponent_ += static_cast<int64_t>(bits >> 52) - 1023;
    bits = (bits & kMantissaBits) | kExponentOfOne;
    std::memcpy(&x, &bits, sizeof bits);
    mantissa_ *= x;
    if (++count_ == 32) Fold();
  }
  double Value() const { return plain_ + std::log(mantissa_) + exponent_ * std::log(2.0); }

 private:
  static constexpr double kInfinity = std::numeric_limits<double>::infinity();
  static constexpr uint64_t kMantissaBits = (uint64_t{1} << 52) - 1;
  static constexpr uint64_t kExponentOfOne = uint64_t{1023} << 52;
  void Fold() {
    int e = 0;
    mantissa_ = std::frexp(mantissa_, &e);
    exponent_ += e;
    count_ = 0;
  }
  double plain_ = 0.0, mantissa_ = 1.0;
  int64_t exponent_ = 0;
  int count_ = 0;
};

// −½Σ[log det Σ_k + e_kᵀΣ_k⁻¹e_k] at variances θ; fills the score and Fisher information in θ.
// Packed cofactors and one logarithm per 32 intervals: this loop runs for every interval at
// every step of the searches (it was most of a calibration's time on real logs).
double LogLikelihood(const JitterData& data, const Eigen::Vector3d& theta, double jitter2,
                     Eigen::Vector3d* score = nullptr, Eigen::Matrix3d* fisher = nullptr) {
  double quadratic = 0.0;
  LogSum log_det;
  double u[3] = {0.0, 0.0, 0.0}, f[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  for (const JitterTerm& term : data.terms) {
    double sigma[6], inverse[6], w[3];
    Covariance(theta, jitter2, term.gram, sigma);
    const double det = InverseOfSymmetric(sigma, inverse);
    // Σ is a positive diagonal plus a positive semi-definite term, so det Σ > 0.
    if (!(det > 0.0)) return -std::numeric_limits<double>::infinity();
    MultiplySymmetric(inverse, term.error, w);
    log_det.Add(det);
    quadratic += term.error[0] * w[0] + term.error[1] * w[1] + term.error[2] * w[2];
    if (score == nullptr) continue;
    u[0] += w[0] * w[0] - inverse[0], u[1] += w[1] * w[1] - inverse[3];
    u[2] += w[2] * w[2] - inverse[5];
    for (int i = 0; i < 6; ++i) f[i] += inverse[i] * inverse[i];
  }
  if (score) *score = 0.5 * Eigen::Vector3d(u[0], u[1], u[2]);
  if (fisher) {
    *fisher << f[0], f[1], f[2], f[1], f[3], f[4], f[2], f[4], f[5];
    *fisher *= 0.5;
  }
  return -0.5 * (log_det.Value() + quadratic);
}

// Floor of the noise variances: σ = 1e-12 m or rad, as RobustNoiseSigma.
constexpr double kMinVariance = 1e-24;

// max over θ of the log-likelihood at σ_j² (Fisher scoring from *theta, which it updates, until
// θ moves by less than `tolerance`, relative).
double ProfileLogLikelihood(const JitterData& data, double jitter_s, bool estimate_noise,
                            Eigen::Vector3d* theta, double tolerance = 1e-10) {
  const double jitter2 = jitter_s * jitter_s;
  if (!estimate_noise) return LogLikelihood(data, *theta, jitter2);
  for (int iteration = 0; iteration < 100; ++iteration) {
    Eigen::Vector3d score;
    Eigen::Matrix3d fisher;
    LogLikelihood(data, *theta, jitter2, &score, &fisher);
    const Eigen::Vector3d step = fisher.ldlt().solve(score);
    const Eigen::Vector3d next = (*theta + step).cwiseMax(*theta / 10.0).cwiseMax(kMinVariance);
    const double change = ((next - *theta).cwiseQuotient(*theta)).cwiseAbs().maxCoeff();
    *theta = next;
    if (!(change > tolerance)) break;
  }
  return LogLikelihood(data, *theta, jitter2);
}

// A grid point's profile only ranks it among the others: θ to 1e-6 leaves its value within
// N·1e-12 of the maximum (the error is quadratic), far below the grid's differences.
constexpr double kGridTolerance = 1e-6;

// The score and Fisher information of the log-likelihood in φ = (θ, s = σ_j²):
// u_a = ½Σ[wᵀA_a w − tr(Σ⁻¹A_a)], I_ab = ½Σ tr(Σ⁻¹A_a Σ⁻¹A_b), w = Σ⁻¹e, A_θi = E_ii, A_s = G_k.
bool JointScore(const JitterData& data, const Eigen::Vector4d& phi, Eigen::Vector4d* score,
                Eigen::Matrix4d* fisher) {
  score->setZero();
  fisher->setZero();
  for (const JitterTerm& term : data.terms) {
    double sigma[6], packed[6];
    Covariance(phi.head<3>(), phi(3), term.gram, sigma);
    if (!(InverseOfSymmetric(sigma, packed) > 0.0)) return false;
    const auto unpack = [](const double p[6]) {
      return (Eigen::Matrix3d() << p[0], p[1], p[2], p[1], p[3], p[4], p[2], p[4], p[5]).finished();
    };
    const Eigen::Matrix3d inverse = unpack(packed), g = unpack(term.gram);
    const Eigen::Vector3d w =
        inverse * Eigen::Vector3d(term.error[0], term.error[1], term.error[2]);
    const Eigen::Matrix3d m = inverse * g;  // Σ⁻¹G.
    score->head<3>() += 0.5 * (w.cwiseAbs2() - inverse.diagonal());
    (*score)(3) += 0.5 * (w.dot(g * w) - m.trace());
    fisher->topLeftCorner<3, 3>() += 0.5 * inverse.cwiseAbs2();
    const Eigen::Vector3d cross = 0.5 * (m * inverse).diagonal();
    fisher->block<3, 1>(0, 3) += cross;
    fisher->block<1, 3>(3, 0) += cross.transpose();
    (*fisher)(3, 3) += 0.5 * (m * m).trace();
  }
  return true;
}

// Fisher scoring jointly in (θ, σ_j²) from (*theta, *jitter_s): the profile's maximum in a few
// passes instead of a search along σ_j with a scoring at every point. False, leaving the outputs,
// when it does not settle at a σ_j strictly within (lo, hi) (a maximum on the boundary σ_j = 0 or
// beyond the bracket: the search decides then).
bool JointMaximum(const JitterData& data, double lo, double hi, Eigen::Vector3d* theta,
                  double* jitter_s) {
  Eigen::Vector4d phi;
  phi << *theta, *jitter_s * *jitter_s;
  for (int iteration = 0; iteration < 50; ++iteration) {
    Eigen::Vector4d score;
    Eigen::Matrix4d fisher;
    if (!JointScore(data, phi, &score, &fisher)) return false;
    const Eigen::LDLT<Eigen::Matrix4d> ldlt(fisher);
    if (ldlt.info() != Eigen::Success) return false;
    // As the profile's scoring: no variance falls by more than 10× in a step.
    const Eigen::Vector4d next =
        (phi + ldlt.solve(score)).cwiseMax(phi / 10.0).cwiseMax(kMinVariance);
    if (!next.allFinite()) return false;
    const double change = ((next - phi).cwiseQuotient(phi)).cwiseAbs().maxCoeff();
    phi = next;
    const double jitter = std::sqrt(phi(3));
    if (jitter < lo / 10.0 || jitter > 10.0 * hi) return false;
    if (change > 1e-10) continue;
    if (!(jitter > lo && jitter < hi)) return false;
    *theta = phi.head<3>();
    *jitter_s = jitter;
    return true;
  }
  return false;
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
  std::vector<size_t> all(intervals.size());
  for (size_t k = 0; k < all.size(); ++k) all[k] = k;
  return IntervalTimeSensitivities(intervals, calibration, all);
}

std::vector<IntervalTimeSensitivity> IntervalTimeSensitivities(
    const std::vector<LaserInterval>& intervals, const LaserCalibration& calibration,
    const std::vector<size_t>& indices) {
  using Jet = ceres::Jet<double, 2>;
  const std::vector<IntervalBoundarySpeeds> speeds = BoundaryWheelSpeeds(intervals);
  const OdometryParams& p = calibration.odometry;
  std::vector<IntervalTimeSensitivity> sensitivities(indices.size());
  for (size_t i = 0; i < indices.size(); ++i) {
    const size_t k = indices[i];
    const Pose2d robot_motion =
        IntervalRobotMotion(p.left_radius_m, p.right_radius_m, p.wheelbase_m, intervals[k]);
    const Eigen::Matrix<Jet, 3, 1> motion =
        ShiftedSensorMotion(calibration, robot_motion, speeds[k], Jet(0.0, 0), Jet(0.0, 1));
    for (int j = 0; j < 3; ++j) {
      sensitivities[i].start(j) = motion(j).v(0);
      sensitivities[i].end(j) = motion(j).v(1);
    }
  }
  return sensitivities;
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
  std::vector<Eigen::Matrix2d> covariances;
  covariances.reserve(intervals.size());
  for (const IntervalBoundarySpeeds& speeds : BoundaryWheelSpeeds(intervals)) {
    covariances.push_back(
        jitter_s * jitter_s *
        (speeds.start * speeds.start.transpose() + speeds.end * speeds.end.transpose()));
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
  for (size_t k : JitterSampleIndices(n, is_inlier, options.max_intervals)) {
    const IntervalTimeSensitivity& g = sensitivities[k];
    const Eigen::Matrix3d gram = g.start * g.start.transpose() + g.end * g.end.transpose();
    data.terms.push_back(
        {{errors[k](0), errors[k](1), errors[k](2)},
         {gram(0, 0), gram(0, 1), gram(0, 2), gram(1, 1), gram(1, 2), gram(2, 2)}});
  }
  IntervalJitterEstimate estimate;
  estimate.intervals_used = static_cast<int>(data.terms.size());
  Eigen::Vector3d theta = noise_sigma.cwiseAbs2().cwiseMax(kMinVariance);
  estimate.log_likelihood_without_jitter =
      ProfileLogLikelihood(data, 0.0, options.estimate_noise, &theta);
  estimate.noise_sigma_without_jitter = estimate.noise_sigma = theta.cwiseSqrt();
  estimate.log_likelihood = estimate.log_likelihood_without_jitter;
  // The jitter that doubles a typical interval's variance sets the grid's scale.
  std::vector<double> relative;
  for (const JitterTerm& term : data.terms) {
    relative.push_back(term.gram[0] / theta(0) + term.gram[3] / theta(1) + term.gram[5] / theta(2));
  }
  if (relative.size() < 2) return estimate;
  std::nth_element(relative.begin(), relative.begin() + relative.size() / 2, relative.end());
  const double median = relative[relative.size() / 2];
  if (!(median > 0.0) || !std::isfinite(median)) return estimate;
  const double scale = 1.0 / std::sqrt(median);

  // Each evaluation starts the scoring where the previous one ended (nearby σ_j: a few steps).
  Eigen::Vector3d warm = theta;
  const auto profile = [&](double jitter_s) {
    return ProfileLogLikelihood(data, jitter_s, options.estimate_noise, &warm);
  };
  const auto rank = [&](double jitter_s) {
    return ProfileLogLikelihood(data, jitter_s, options.estimate_noise, &warm, kGridTolerance);
  };
  // Joint scoring from σ_j = start, with θ profiled there first (the grid's warm θ belongs to
  // its last point).
  const auto joint = [&](double lo, double hi, double start, double* jitter_s) {
    if (!options.estimate_noise || !options.joint_scoring) return false;
    Eigen::Vector3d start_theta = warm;
    ProfileLogLikelihood(data, start, true, &start_theta, kGridTolerance);
    double found = start;
    if (!JointMaximum(data, lo, hi, &start_theta, &found)) return false;
    warm = start_theta;
    *jitter_s = found;
    return true;
  };
  double jitter_s = 0.0, value = 0.0;
  if (!(options.previous_jitter_s > 0.0) ||
      !NearPrevious(profile, joint, options.previous_jitter_s, &jitter_s, &value)) {
    warm = theta;
    SearchFromGrid(profile, rank, joint, scale, options.grid_points,
                   estimate.log_likelihood_without_jitter, &jitter_s, &value);
  }
  Eigen::Vector3d theta_best = warm;
  ProfileLogLikelihood(data, jitter_s, options.estimate_noise, &theta_best);

  estimate.jitter_s = jitter_s;
  estimate.noise_sigma = theta_best.cwiseSqrt();
  estimate.log_likelihood = value;
  estimate.lr_statistic = std::max(0.0, 2.0 * (value - estimate.log_likelihood_without_jitter));
  // On the boundary σ_j = 0 the statistic is ½χ²₀ + ½χ²₁.
  estimate.p_value =
      estimate.lr_statistic > 0.0 ? 0.5 * std::erfc(std::sqrt(estimate.lr_statistic / 2.0)) : 1.0;
  estimate.significant = estimate.p_value < options.significance;
  // σ of σ_j from the profile's curvature (ℓ is even in σ_j, so at 0 the one-sided difference).
  const double h = std::max(0.1 * jitter_s, 0.01 * scale);
  const double curvature =
      jitter_s > h ? (profile(jitter_s + h) - 2.0 * value + profile(jitter_s - h)) / (h * h)
                   : 2.0 * (profile(jitter_s + h) - profile(jitter_s)) / (h * h);
  estimate.jitter_stddev_s =
      curvature < 0.0 ? 1.0 / std::sqrt(-curvature) : std::numeric_limits<double>::infinity();
  return estimate;
}

IntervalJitterEstimate EstimateIntervalJitter(const std::vector<LaserInterval>& intervals,
                                              const LaserCalibration& calibration,
                                              const Eigen::Vector3d& noise_sigma,
                                              const std::vector<bool>& is_inlier,
                                              const IntervalJitterOptions& options) {
  // Errors and sensitivities of the sampled intervals only (a million-interval log samples 2 %).
  const std::vector<size_t> sample =
      JitterSampleIndices(intervals.size(), is_inlier, options.max_intervals);
  const LaserParamVector p = calibration.ToVector();
  std::vector<Eigen::Vector3d> errors;
  errors.reserve(sample.size());
  for (size_t k : sample) {
    errors.push_back(LaserResidual::Error(intervals[k], p.data(), p.data() + 3));
  }
  IntervalJitterOptions all = options;
  all.max_intervals = std::max<int>(options.max_intervals, static_cast<int>(sample.size()));
  return EstimateIntervalJitter(errors, IntervalTimeSensitivities(intervals, calibration, sample),
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
