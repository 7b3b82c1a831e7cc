#include <calib/core/huge_pages.h>
#include <calib/problems/laser/laser_residual.h>
#include <calib/solvers/common/parallel_chunks.h>
#include <calib/solvers/laser/laser_consistency_terms.h>
#include <calib/solvers/laser/laser_motion.h>
#include <ceres/jet.h>

#include <algorithm>
#include <cmath>

namespace calib::consistency_internal {
namespace {

// Below this many intervals per chunk a thread costs more than it saves.
constexpr size_t kMinChunk = 5000;

template <typename T>
T Travel(const Pose2d& sensor_motion, const Pose2<T>& base_T_sensor) {
  using std::cos;
  using std::sin;
  const Pose2<T> o =
      Compose(Compose(base_T_sensor, Pose2<T>(sensor_motion.cast<T>())), Inverse(base_T_sensor));
  const T half = o(2) / T(2);
  const T sinc = ceres::abs(half) < T(1e-4) ? T(1) - half * half / T(6) : sin(half) / half;
  return (o(0) * cos(half) + o(1) * sin(half)) / sinc;
}

// Rescues the fit's outliers that are timing artefacts (see ComputeTerms).
void RescueTimingOutliers(const std::vector<LaserInterval>& intervals,
                          const Eigen::Vector3d& noise_sigma, std::vector<IntervalTerms>* terms) {
  std::vector<IntervalTerms>& t = *terms;
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

}  // namespace

double ForwardTravel(const Pose2d& sensor_motion, const Pose2d& base_T_sensor,
                     Eigen::Vector3d* gradient) {
  using Jet3 = ceres::Jet<double, 3>;
  const Pose2<Jet3> mounting(Jet3(base_T_sensor(0), 0), Jet3(base_T_sensor(1), 1),
                             Jet3(base_T_sensor(2), 2));
  const Jet3 travel = Travel(sensor_motion, mounting);
  if (gradient != nullptr) *gradient = travel.v;
  return travel.a;
}

LogTerms ComputeTerms(const std::vector<LaserInterval>& intervals, const LaserCalibration& c,
                      const Eigen::Vector3d& noise_sigma, const std::vector<bool>& is_inlier,
                      LaserParamMatrix* hessian, int num_threads) {
  const OdometryParams& odo = c.odometry;
  const Eigen::Vector3d weight = noise_sigma.cwiseMax(1e-12).cwiseAbs2().cwiseInverse();
  const double still_travel_m = 0.5 * std::min(noise_sigma(0), noise_sigma(1));
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  const LaserParamVector v = c.ToVector();
  LogTerms log{&intervals, {}};
  ReserveOnHugePages(&log.terms, intervals.size());
  log.terms.resize(intervals.size());
  std::vector<LaserParamMatrix> hessians(ChunkCount(intervals.size(), num_threads, kMinChunk),
                                         LaserParamMatrix::Zero());
  ParallelChunks(
      intervals.size(), num_threads, kMinChunk, [&](size_t chunk, size_t begin, size_t end) {
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
          t.travel_measured = ForwardTravel(in.sensor_motion, c.base_T_sensor, &travel_gradient);
          t.travel_gradient = travel_gradient.cast<float>();
          t.still = wheel.cwiseAbs().sum() < 1e-6 ||
                    (std::abs(t.rotation_predicted) <= 0.5 * noise_sigma(2) &&
                     std::abs(t.travel_predicted) <= still_travel_m);
          if (!t.counted) continue;
          Eigen::Matrix<double, 3, kNumLaserParams> jacobian;
          Eigen::Vector3d e;
          LaserResidual::Linearize(in, identity, v.data(), v.data() + 3, &e, &jacobian);
          t.influence = (jacobian.transpose() * weight.asDiagonal() * e).cast<float>();
          h += jacobian.transpose() * weight.asDiagonal() * jacobian;
        }
        hessians[chunk] = h;
      });
  for (const LaserParamMatrix& h : hessians) *hessian += h;
  RescueTimingOutliers(intervals, noise_sigma, &log.terms);
  return log;
}

LaserParamMatrix InfluenceLongRun(const std::vector<LogTerms>& logs, int lag, int num_threads) {
  LaserParamMatrix s = LaserParamMatrix::Zero();
  for (const LogTerms& log : logs) {
    const std::vector<IntervalTerms>& t = log.terms;
    std::vector<LaserParamMatrix> sums(ChunkCount(t.size(), num_threads, kMinChunk),
                                       LaserParamMatrix::Zero());
    ParallelChunks(t.size(), num_threads, kMinChunk, [&](size_t chunk, size_t begin, size_t end) {
      // Σ_k ψ_kψ_kᵀ + C + Cᵀ with C = Σ_k ψ_k·(Σ_j w_j ψ_{k+j})ᵀ: one outer product per
      // interval, the lags summed as a running vector.
      LaserParamMatrix cross = LaserParamMatrix::Zero();
      LaserParamMatrix sum = LaserParamMatrix::Zero();  // Stored once (see ComputeTerms).
      const auto psi_at = [&](long k) {
        return k < static_cast<long>(t.size()) ? t[k].Influence() : Vector6::Zero().eval();
      };
      BartlettAhead<Vector6, decltype(psi_at)> ahead(psi_at, lag, static_cast<long>(begin));
      for (size_t k = begin; k < end; ++k, ahead.Advance()) {
        const Vector6 psi = t[k].Influence();
        sum.noalias() += psi * psi.transpose();
        cross.noalias() += psi * ahead.value().transpose();
      }
      sums[chunk] = sum + cross + cross.transpose();
    });
    for (const LaserParamMatrix& sum : sums) s += sum;
  }
  return s;
}

}  // namespace calib::consistency_internal
