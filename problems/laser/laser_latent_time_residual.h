#ifndef CALIB_PROBLEMS_LASER_LASER_LATENT_TIME_RESIDUAL_H_
#define CALIB_PROBLEMS_LASER_LASER_LATENT_TIME_RESIDUAL_H_

#include <calib/core/se2.h>
#include <calib/core/timing/encoder_integration.h>
#include <calib/problems/laser/laser_residual.h>
#include <ceres/dynamic_autodiff_cost_function.h>

#include <Eigen/Core>
#include <array>
#include <vector>

namespace calib {

// Where the time of one end of an interval comes from, as parameter-block indices of the residual
// (−1: a constant), and the encoder samples that bracket it.
struct LatentTimeEnd {
  // Stamp model: t = stamp + δ, δ the block `time_block` (size 1).
  // Clock model: t = t0 + P·n + a·u², (t0, P, a) the block `time_block` (size 3).
  bool clock = false;
  int time_block = -1;
  double stamp_s = 0.0;
  double index = 0.0;      // n.
  double curvature = 0.0;  // u².
  // The encoder samples j, j + 1 around the end: e = stamp + η, η the block (size 1) or 0.
  std::array<int, 2> encoder_block = {-1, -1};
  std::array<double, 2> encoder_stamp_s = {0.0, 0.0};
  std::array<double, 2> left_rad = {0.0, 0.0};
  std::array<double, 2> right_rad = {0.0, 0.0};
  // Their wheel rates (WheelRatesAt), held fixed while the times move.
  std::array<double, 2> left_rate = {0.0, 0.0};
  std::array<double, 2> right_rate = {0.0, 0.0};
};

// Laser interval residual with latent sample times. The wheel angles at the ends t_a, t_b lie on
// the cubic through their bracketing encoder samples (at their latent times e_j) with the samples'
// wheel rates m_j (HermiteWheelAngle): with Δ = e_{j+1} − e_j and s = (t − e_j)/Δ,
//   α(t) = α_j + (3s² − 2s³)·(α_{j+1} − α_j) + Δ·[(s³ − 2s² + s)·m_j + (s³ − s²)·m_{j+1}],
// the robot displacement o chains constant-speed arcs α(t_a) → α_{j_a+1} → … → α_{j_b} → α(t_b),
// and, as in LaserResidual, r = L·SensorMotionError(ℓ⁻¹ ∘ o ∘ ℓ, ŝ).
// Blocks: 0 odometry (r_l, r_r, b), 1 base_T_sensor (x, y, θ), then the time blocks the ends name.
// The interval (its measured motion and interior angles) is copied; `sqrt_information` is held.
class LaserLatentTimeResidual {
 public:
  LaserLatentTimeResidual(const Pose2d& sensor_motion, const Eigen::Matrix3d* sqrt_information,
                          const LatentTimeEnd& start, const LatentTimeEnd& end,
                          std::vector<double> interior_left_rad,
                          std::vector<double> interior_right_rad)
      : sensor_motion_(sensor_motion),
        sqrt_information_(sqrt_information),
        start_(start),
        end_(end),
        interior_left_(std::move(interior_left_rad)),
        interior_right_(std::move(interior_right_rad)) {}

  template <typename T>
  bool operator()(T const* const* parameters, T* residual) const {
    T ends[4];
    AnglesAt(start_, parameters, &ends[0], &ends[1]);
    AnglesAt(end_, parameters, &ends[2], &ends[3]);
    FromEndAngles(parameters[0], parameters[1], ends, residual);
    return true;
  }

  // The residual from the wheel angles at the ends, (left, right) at t_a then at t_b.
  template <typename T>
  void FromEndAngles(const T* odometry, const T* base_T_sensor, const T* ends, T* residual) const {
    const int count = static_cast<int>(interior_left_.size()) + 2;
    T left[kMaxInline], right[kMaxInline];
    std::vector<T> left_heap, right_heap;
    T* l = left;
    T* r = right;
    if (count > kMaxInline) {
      left_heap.resize(count);
      right_heap.resize(count);
      l = left_heap.data();
      r = right_heap.data();
    }
    l[0] = ends[0], r[0] = ends[1];
    for (int i = 0; i + 2 < count; ++i) {
      l[i + 1] = T(interior_left_[i]);
      r[i + 1] = T(interior_right_[i]);
    }
    l[count - 1] = ends[2], r[count - 1] = ends[3];
    const Pose2<T> robot_motion =
        WheelAngleChainDisplacement(odometry[0], odometry[1], odometry[2], l, r, count);
    const Pose2<T> mounting(base_T_sensor[0], base_T_sensor[1], base_T_sensor[2]);
    const Pose2<T> predicted = SensorMotionFromRobotMotion(mounting, robot_motion);
    Eigen::Map<Eigen::Matrix<T, 3, 1>> whitened(residual);
    whitened = sqrt_information_->cast<T>() * SensorMotionError(predicted, sensor_motion_);
  }

  const LatentTimeEnd& start() const { return start_; }
  const LatentTimeEnd& end() const { return end_; }

  // `block_sizes` lists the sizes of every block in the order the ends index them.
  // By automatic differentiation through the time blocks (the reference for LaserLatentTimeCost).
  static ceres::CostFunction* CreateAutoDiff(const Pose2d& sensor_motion,
                                             const Eigen::Matrix3d* sqrt_information,
                                             const LatentTimeEnd& start, const LatentTimeEnd& end,
                                             std::vector<double> interior_left_rad,
                                             std::vector<double> interior_right_rad,
                                             const std::vector<int>& block_sizes) {
    auto* cost = new ceres::DynamicAutoDiffCostFunction<LaserLatentTimeResidual, kStride>(
        new LaserLatentTimeResidual(sensor_motion, sqrt_information, start, end,
                                    std::move(interior_left_rad), std::move(interior_right_rad)));
    for (const int size : block_sizes) cost->AddParameterBlock(size);
    cost->SetNumResiduals(3);
    return cost;
  }

  // The time of an end, and the wheel angles there.
  template <typename T>
  static T Time(const LatentTimeEnd& end, T const* const* parameters) {
    if (end.clock) {
      const T* c = parameters[end.time_block];
      return c[0] + c[1] * end.index + c[2] * end.curvature;
    }
    return end.time_block < 0 ? T(end.stamp_s) : T(end.stamp_s) + parameters[end.time_block][0];
  }

  template <typename T>
  static void AnglesAt(const LatentTimeEnd& end, T const* const* parameters, T* left, T* right) {
    T e[2];
    for (int i = 0; i < 2; ++i) {
      e[i] = T(end.encoder_stamp_s[i]);
      if (end.encoder_block[i] >= 0) e[i] += parameters[end.encoder_block[i]][0];
    }
    const T t = Time(end, parameters);
    *left = HermiteWheelAngle(t, e[0], e[1], end.left_rad[0], end.left_rad[1], end.left_rate[0],
                              end.left_rate[1]);
    *right = HermiteWheelAngle(t, e[0], e[1], end.right_rad[0], end.right_rad[1], end.right_rate[0],
                               end.right_rate[1]);
  }

 private:
  static constexpr int kStride = 8;
  static constexpr int kMaxInline = 16;

  Pose2d sensor_motion_;
  const Eigen::Matrix3d* sqrt_information_;
  LatentTimeEnd start_;
  LatentTimeEnd end_;
  std::vector<double> interior_left_;
  std::vector<double> interior_right_;
};

}  // namespace calib

#endif  // CALIB_PROBLEMS_LASER_LASER_LATENT_TIME_RESIDUAL_H_
