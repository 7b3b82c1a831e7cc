#include <calib/core/huge_pages.h>
#include <calib/core/sin_cos.h>
#include <calib/problems/laser/laser_residual.h>
#include <calib/solvers/common/parallel_chunks.h>
#include <calib/solvers/laser/laser_consistency_terms.h>
#include <calib/solvers/laser/laser_motion.h>

#include <algorithm>
#include <cmath>

namespace calib::consistency_internal {
namespace {

// Rescues the fit's outliers that are timing artefacts (see ComputeTerms).
void RescueTimingOutliers(const std::vector<LaserInterval>& intervals,
                          const Eigen::Vector3d& noise_sigma, TermsVector* terms) {
  TermsVector& t = *terms;
  const double rotation_limit = 4.0 * std::sqrt(2.0) * noise_sigma(2);
  const double travel_limit = 4.0 * std::sqrt(2.0) * noise_sigma.head<2>().maxCoeff();
  const auto agrees = [&](size_t a, size_t b) {
    return !intervals[b].gap_before &&
           std::abs(t[a].rotation_difference() + t[b].rotation_difference()) <= rotation_limit &&
           std::abs(t[a].travel_difference() + t[b].travel_difference()) <= travel_limit;
  };
  std::vector<bool> rescued(t.size(), false);
  for (size_t k = 0; k < t.size(); ++k) {
    if (t[k].counted) continue;
    rescued[k] = (k > 0 && agrees(k - 1, k)) || (k + 1 < t.size() && agrees(k, k + 1));
  }
  for (size_t k = 0; k < t.size(); ++k) t[k].counted = t[k].counted || rescued[k];
}

// Andrews' lag from a series' sums Σx_k² and Σx_k·x_{k+1} over its n counted intervals.
int AndrewsLag(double lag0, double lag1, long n) {
  if (n < 8 || !(lag0 > 0.0)) return 1;
  const double rho = std::clamp(lag1 / lag0, -0.97, 0.97);
  const double alpha = 4.0 * rho * rho / ((1 - rho) * (1 - rho) * (1 + rho) * (1 + rho));
  const double lag = std::ceil(1.1447 * std::cbrt(alpha * static_cast<double>(n)));
  return static_cast<int>(std::clamp(lag, 1.0, static_cast<double>(n / 4)));
}

}  // namespace

std::array<int, 2> AutomaticLags(const std::vector<LogTerms>& logs, int num_threads) {
  struct Sums {
    double lag0[2] = {0.0, 0.0}, lag1[2] = {0.0, 0.0};
    long n = 0;
    void Add(const Sums& o) {
      n += o.n;
      for (int q = 0; q < 2; ++q) lag0[q] += o.lag0[q], lag1[q] += o.lag1[q];
    }
  };
  const auto series = [](const IntervalTerms& t, int q) {
    return q == 0 ? t.rotation_difference() : t.travel_difference();
  };
  Sums total;
  for (const LogTerms& log : logs) {
    const TermsVector& t = log.terms;
    std::vector<Sums> chunks(SplitCount(t.size(), kMinChunkIntervals));
    ParallelSplit(t.size(), num_threads, kMinChunkIntervals,
                  [&](size_t chunk, size_t begin, size_t end) {
                    Sums s;
                    for (size_t k = begin; k < end; ++k) {
                      if (!t[k].counted) continue;
                      ++s.n;
                      const bool next = k + 1 < t.size() && t[k + 1].counted;
                      for (int q = 0; q < 2; ++q) {
                        const double x = series(t[k], q);
                        s.lag0[q] += x * x;
                        if (next) s.lag1[q] += x * series(t[k + 1], q);
                      }
                    }
                    chunks[chunk] = s;
                  });
    for (const Sums& s : chunks) total.Add(s);
  }
  return {AndrewsLag(total.lag0[0], total.lag1[0], total.n),
          AndrewsLag(total.lag0[1], total.lag1[1], total.n)};
}

double ForwardTravel(const Pose2d& sensor_motion, const Pose2d& base_T_sensor,
                     Eigen::Vector3d* gradient) {
  return ForwardTravel(sensor_motion, SensorMounting(base_T_sensor.data()), gradient);
}

// With ℓ = (p, θ_ℓ), s = (t, φ): o = ℓ ∘ s ∘ ℓ⁻¹ = (R(θ_ℓ)·t + (I − R(φ))·p, φ), and with
// u = (cos(φ/2), sin(φ/2)) / sinc(φ/2) the travel is uᵀo_xy; ∂/∂p = (I − R(φ))ᵀu and
// ∂/∂θ_ℓ = uᵀR'(θ_ℓ)·t. One sine and cosine per interval, of φ/2.
double ForwardTravel(const Pose2d& sensor_motion, const SensorMounting& mounting,
                     Eigen::Vector3d* gradient) {
  const double half = sensor_motion(2) / 2.0;
  double sh, ch;
  SinCos(half, &sh, &ch);
  const double sinc = std::abs(half) < 1e-4 ? 1.0 - half * half / 6.0 : sh / half;
  const Eigen::Vector2d u = Eigen::Vector2d(ch, sh) / sinc;
  const double cf = 1.0 - 2.0 * sh * sh, sf = 2.0 * sh * ch;  // cos φ, sin φ.
  const double cl = mounting.cos_theta, sl = mounting.sin_theta;
  const double tx = sensor_motion(0), ty = sensor_motion(1);
  const double px = mounting.pose[0], py = mounting.pose[1];
  const Eigen::Vector2d o(cl * tx - sl * ty + (1.0 - cf) * px + sf * py,
                          sl * tx + cl * ty - sf * px + (1.0 - cf) * py);
  if (gradient != nullptr) {
    *gradient << (1.0 - cf) * u(0) - sf * u(1), sf * u(0) + (1.0 - cf) * u(1),
        u.dot(Eigen::Vector2d(-sl * tx - cl * ty, cl * tx - sl * ty));
  }
  return u.dot(o);
}

LogTerms ComputeTerms(const std::vector<LaserInterval>& intervals, const LaserCalibration& c,
                      const Eigen::Vector3d& noise_sigma, const std::vector<bool>& is_inlier,
                      LaserParamMatrix* hessian, int num_threads) {
  const OdometryParams& odo = c.odometry;
  const Eigen::Vector3d weight = noise_sigma.cwiseMax(1e-12).cwiseAbs2().cwiseInverse();
  const double still_travel_m = 0.5 * std::min(noise_sigma(0), noise_sigma(1));
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  const LaserParamVector v = c.ToVector();
  const SensorMounting mounting(v.data() + 3);
  LogTerms log{&intervals, {}};
  ReserveOnHugePages(&log.terms, intervals.size());
  log.terms.resize(intervals.size());
  std::vector<LaserParamMatrix> hessians(SplitCount(intervals.size(), kMinChunkIntervals),
                                         LaserParamMatrix::Zero());
  ParallelSplit(
      intervals.size(), num_threads, kMinChunkIntervals,
      [&](size_t chunk, size_t begin, size_t end) {
        // On the thread's stack: side by side in `hessians` the sums would share cache lines.
        LaserParamMatrix h = LaserParamMatrix::Zero();
        for (size_t k = begin; k < end; ++k) {
          const LaserInterval& in = intervals[k];
          IntervalTerms& t = log.terms[k];
          t.counted = is_inlier.empty() || is_inlier[k];
          const Eigen::Vector2d wheel = IntervalWheelRotation(in);
          // r·Δφ summed over the steps is r·(total Δφ): the totals need no integration.
          t.rotation_predicted =
              (odo.right_radius_m * wheel(1) - odo.left_radius_m * wheel(0)) / odo.wheelbase_m;
          t.travel_predicted = (odo.left_radius_m * wheel(0) + odo.right_radius_m * wheel(1)) / 2.0;
          t.rotation_measured = in.sensor_motion(2);
          Eigen::Vector3d travel_gradient;
          t.travel_measured = ForwardTravel(in.sensor_motion, mounting, &travel_gradient);
          t.travel_gradient = travel_gradient.cast<float>();
          t.still = wheel.cwiseAbs().sum() < 1e-6 ||
                    (std::abs(t.rotation_predicted) <= 0.5 * noise_sigma(2) &&
                     std::abs(t.travel_predicted) <= still_travel_m);
          if (!t.counted) {
            t.score.setZero();
            continue;
          }
          Eigen::Matrix<double, 3, kNumLaserParams> jacobian;
          Eigen::Vector3d e;
          LaserResidual::Linearize(in, identity, v.data(), mounting, &e, &jacobian);
          const Eigen::Matrix<double, 3, kNumLaserParams> weighted = weight.asDiagonal() * jacobian;
          t.score = (weighted.transpose() * e).cast<float>();
          // JᵀWJ by its upper triangle (mirrored once after the pass), as FusedNormalCost does.
          for (int b = 0; b < kNumLaserParams; ++b) {
            for (int a = 0; a <= b; ++a) h(a, b) += weighted.col(a).dot(jacobian.col(b));
          }
        }
        hessians[chunk] = h;
      });
  LaserParamMatrix sum = LaserParamMatrix::Zero();
  for (const LaserParamMatrix& h : hessians) sum += h;
  sum.triangularView<Eigen::StrictlyLower>() = sum.transpose();
  *hessian += sum;
  RescueTimingOutliers(intervals, noise_sigma, &log.terms);
  return log;
}

std::vector<LaserParamMatrix> ScoreLongRun(const std::vector<LogTerms>& logs,
                                           const std::vector<int>& lags, int num_threads) {
  const size_t num_lags = lags.size();
  std::vector<LaserParamMatrix> s(num_lags, LaserParamMatrix::Zero());
  for (const LogTerms& log : logs) {
    const TermsVector& t = log.terms;
    const long n = static_cast<long>(t.size());
    std::vector<std::vector<LaserParamMatrix>> sums(SplitCount(t.size(), kMinChunkIntervals));
    ParallelSplit(
        t.size(), num_threads, kMinChunkIntervals, [&](size_t chunk, size_t begin, size_t end) {
          // Σ_k g_kg_kᵀ + C + Cᵀ with C = Σ_k g_k·(Σ_j w_j g_{k+j})ᵀ: one outer product per
          // interval and lag, the lags summed as running vectors.
          const auto g_at = [&](long k) { return k < n ? t[k].Score() : Vector6::Zero().eval(); };
          using Ahead = BartlettAhead<Vector6, decltype(g_at)>;
          std::vector<Ahead> ahead;
          for (int lag : lags) ahead.emplace_back(g_at, lag, static_cast<long>(begin));
          LaserParamMatrix square = LaserParamMatrix::Zero();
          std::vector<LaserParamMatrix> cross(num_lags, LaserParamMatrix::Zero());
          for (size_t k = begin; k < end; ++k) {
            const Vector6 g = t[k].Score();
            square.noalias() += g * g.transpose();
            for (size_t l = 0; l < num_lags; ++l) {
              cross[l].noalias() += g * ahead[l].value().transpose();
              ahead[l].Advance();
            }
          }
          sums[chunk].resize(num_lags);
          for (size_t l = 0; l < num_lags; ++l) {
            sums[chunk][l] = square + cross[l] + cross[l].transpose();
          }
        });
    for (const std::vector<LaserParamMatrix>& chunk : sums) {
      for (size_t l = 0; l < num_lags; ++l) s[l] += chunk[l];
    }
  }
  return s;
}

}  // namespace calib::consistency_internal
