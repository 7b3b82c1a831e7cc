#include <calib/core/diff_drive.h>
#include <calib/core/laser/laser_log.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/core/se2.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <vector>

namespace calib {
namespace {

// Constant speeds per interval, no noise, no effects: the base model is exact.
LaserSimOptions ExactOptions() {
  LaserSimOptions options;
  options.speed_time_constant_s = 0.0;
  options.scan_noise_sigma.setZero();
  options.num_intervals = 1000;
  return options;
}

Pose2d BaseModel(const OdometryParams& odometry, const Pose2d& base_T_sensor,
                 const LaserInterval& interval) {
  return SensorMotionFromRobotMotion(
      base_T_sensor, IntervalRobotMotion(odometry.left_radius_m, odometry.right_radius_m,
                                         odometry.wheelbase_m, interval));
}

// o = ℓ ∘ s ∘ ℓ⁻¹, the inverse of SensorMotionFromRobotMotion.
Pose2d RobotMotion(const Pose2d& base_T_sensor, const Pose2d& sensor_motion) {
  return Compose(base_T_sensor, Compose(sensor_motion, Inverse(base_T_sensor)));
}

// Constant-speed arc of an interval's wheel speeds over dt.
Pose2d Arc(const OdometryParams& odometry, const LaserInterval& interval, double dt) {
  return WheelStepDisplacement(odometry.left_radius_m, odometry.right_radius_m,
                               odometry.wheelbase_m, interval.left_speed * dt,
                               interval.right_speed * dt);
}

double PoseError(const Pose2d& a, const Pose2d& b) {
  return std::max({std::abs(a(0) - b(0)), std::abs(a(1) - b(1)), std::abs(WrapAngle(a(2) - b(2)))});
}

double Forward(const OdometryParams& p, double left, double right) {
  return 0.5 * (p.left_radius_m * left + p.right_radius_m * right);
}

double Angular(const OdometryParams& p, double left, double right) {
  return (p.right_radius_m * right - p.left_radius_m * left) / p.wheelbase_m;
}

TEST(LaserSimulatorTest, ConstantSpeedsMatchTheBaseModelExactly) {
  for (const LaserTrajectory kind :
       {LaserTrajectory::kRich, LaserTrajectory::kStraight, LaserTrajectory::kPureRotation,
        LaserTrajectory::kConstantArc}) {
    for (const int record_steps : {0, 7}) {
      LaserSimOptions options = ExactOptions();
      options.trajectory = kind;
      options.record_steps = record_steps;
      LaserSimTruth truth;
      const LaserLog log = SimulateLaserLog(options, &truth);
      ASSERT_EQ(log.intervals.size(), 1000u);
      EXPECT_TRUE(log.has_timestamps);
      double max_error = 0.0;
      for (size_t k = 0; k < log.intervals.size(); ++k) {
        const LaserInterval& interval = log.intervals[k];
        EXPECT_EQ(interval.record, static_cast<int>(k + 1));
        EXPECT_EQ(interval.steps.size(), static_cast<size_t>(record_steps));
        EXPECT_NEAR(interval.duration_s, options.mean_interval_s, options.interval_jitter_s);
        EXPECT_FALSE(interval.gap_before);
        if (k == 0) {
          EXPECT_EQ(interval.start_s, 0.0);
        } else {
          const LaserInterval& previous = log.intervals[k - 1];
          EXPECT_NEAR(interval.start_s, previous.start_s + previous.duration_s, 1e-9);
        }
        max_error = std::max(max_error,
                             PoseError(interval.sensor_motion,
                                       BaseModel(truth.odometry, truth.base_T_sensor, interval)));
      }
      EXPECT_LT(max_error, 1e-12) << "trajectory " << static_cast<int>(kind);
    }
  }
}

TEST(LaserSimulatorTest, FillsTheTruth) {
  LaserSimOptions options = ExactOptions();
  options.effects.lateral_slip_s = 0.01;
  options.outlier_fraction = 0.1;
  LaserSimTruth truth;
  const LaserLog log = SimulateLaserLog(options, &truth);
  EXPECT_EQ(truth.odometry.left_radius_m, options.odometry.left_radius_m);
  EXPECT_EQ(truth.odometry.right_radius_m, options.odometry.right_radius_m);
  EXPECT_EQ(truth.odometry.wheelbase_m, options.odometry.wheelbase_m);
  EXPECT_EQ(truth.base_T_sensor, options.base_T_sensor);
  EXPECT_EQ(truth.effects.lateral_slip_s, 0.01);
  EXPECT_EQ(truth.is_outlier.size(), log.intervals.size());
}

TEST(LaserSimulatorTest, DegenerateOptionsGiveAnEmptyLog) {
  LaserSimOptions options;
  options.num_intervals = 0;
  EXPECT_TRUE(SimulateLaserLog(options).intervals.empty());
  options.num_intervals = 10;
  options.mean_interval_s = 0.0;
  EXPECT_TRUE(SimulateLaserLog(options).intervals.empty());
  EXPECT_TRUE(SimulateLaserStreams(options, 100.0).sensor_poses.empty());
}

// Smooth speeds: the step model converges to the continuous truth at second order, the
// constant-speed model does not.
TEST(LaserSimulatorTest, SmoothSpeedsMatchTheStepModel) {
  LaserSimOptions options;
  options.scan_noise_sigma.setZero();
  options.num_intervals = 500;
  const auto errors = [&](int record_steps) {
    options.record_steps = record_steps;
    LaserSimTruth truth;
    const LaserLog log = SimulateLaserLog(options, &truth);
    double step_error = 0.0;
    double constant_error = 0.0;
    for (LaserInterval interval : log.intervals) {
      step_error =
          std::max(step_error, PoseError(interval.sensor_motion,
                                         BaseModel(truth.odometry, truth.base_T_sensor, interval)));
      interval.steps.clear();
      constant_error = std::max(
          constant_error, PoseError(interval.sensor_motion,
                                    BaseModel(truth.odometry, truth.base_T_sensor, interval)));
    }
    return std::make_pair(step_error, constant_error);
  };
  const auto [error_50, constant_error] = errors(50);
  const double error_400 = errors(400).first;
  EXPECT_LT(error_50, 1e-7);
  EXPECT_GT(constant_error, 100.0 * error_50);
  EXPECT_GT(constant_error, 1e-6);
  // Eight times finer steps: about 64 times smaller error, as long as the truth is exact.
  EXPECT_LT(error_400, error_50 / 30.0);
  EXPECT_GT(error_400, error_50 / 130.0);
}

TEST(LaserSimulatorTest, ScanNoiseHasTheRequestedSigma) {
  LaserSimOptions options;
  options.num_intervals = 20000;
  options.scan_noise_sigma = Eigen::Vector3d(0.002, 0.001, 0.003);
  const LaserLog noisy = SimulateLaserLog(options);
  options.scan_noise_sigma.setZero();
  const LaserLog clean = SimulateLaserLog(options);
  ASSERT_EQ(noisy.intervals.size(), clean.intervals.size());
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Vector3d sum_squares = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < noisy.intervals.size(); ++k) {
    // Noise changes only sm: the same seed gives the same motion and wheel speeds.
    EXPECT_EQ(noisy.intervals[k].left_speed, clean.intervals[k].left_speed);
    Pose2d error = noisy.intervals[k].sensor_motion - clean.intervals[k].sensor_motion;
    error(2) = WrapAngle(error(2));
    sum += error;
    sum_squares += error.cwiseAbs2();
  }
  const double n = static_cast<double>(noisy.intervals.size());
  const Eigen::Vector3d sigma(0.002, 0.001, 0.003);
  for (int j = 0; j < 3; ++j) {
    const double mean = sum(j) / n;
    const double std = std::sqrt(sum_squares(j) / n - mean * mean);
    EXPECT_NEAR(std, sigma(j), 0.05 * sigma(j)) << "component " << j;
    EXPECT_LT(std::abs(mean), 4.0 * sigma(j) / std::sqrt(n)) << "component " << j;
  }
}

TEST(LaserSimulatorTest, WheelSpeedNoiseHasTheRequestedSigma) {
  LaserSimOptions options = ExactOptions();
  options.num_intervals = 20000;
  options.record_steps = 3;
  const LaserLog clean = SimulateLaserLog(options);
  options.wheel_speed_noise = 0.01;
  const LaserLog noisy = SimulateLaserLog(options);
  double sum_squares = 0.0;
  for (size_t k = 0; k < noisy.intervals.size(); ++k) {
    const LaserInterval& interval = noisy.intervals[k];
    sum_squares += std::pow(interval.left_speed - clean.intervals[k].left_speed, 2) +
                   std::pow(interval.right_speed - clean.intervals[k].right_speed, 2);
    // Steps still sum to φ·T.
    double left = 0.0;
    double right = 0.0;
    for (const WheelStep& step : interval.steps) {
      left += step.left_rad;
      right += step.right_rad;
    }
    EXPECT_NEAR(left, interval.left_speed * interval.duration_s, 1e-12);
    EXPECT_NEAR(right, interval.right_speed * interval.duration_s, 1e-12);
    EXPECT_EQ(interval.sensor_motion, clean.intervals[k].sensor_motion);
  }
  EXPECT_NEAR(std::sqrt(sum_squares / (2.0 * noisy.intervals.size())), 0.01, 0.0005);
}

TEST(LaserSimulatorTest, OutliersAreFlaggedAndGross) {
  for (const bool with_noise : {true, false}) {
    LaserSimOptions options;
    options.num_intervals = 2000;
    if (!with_noise) options.scan_noise_sigma.setZero();
    const LaserLog clean = SimulateLaserLog(options);
    options.outlier_fraction = 0.1;
    LaserSimTruth truth;
    const LaserLog log = SimulateLaserLog(options, &truth);
    ASSERT_EQ(truth.is_outlier.size(), 2000u);
    const int count = std::count(truth.is_outlier.begin(), truth.is_outlier.end(), true);
    EXPECT_EQ(count, 200);
    const Eigen::Vector3d sigma = LaserSimOptions().scan_noise_sigma;
    std::vector<double> normalized_errors;
    for (size_t k = 0; k < log.intervals.size(); ++k) {
      const Pose2d& sm = log.intervals[k].sensor_motion;
      const Pose2d& clean_sm = clean.intervals[k].sensor_motion;
      if (!truth.is_outlier[k]) {
        EXPECT_EQ(sm, clean_sm) << k;
        continue;
      }
      EXPECT_GT(PoseError(sm, clean_sm), 1e-5) << k;
      normalized_errors.push_back((sm - clean_sm).cwiseAbs().cwiseQuotient(sigma).maxCoeff());
    }
    // Gross errors are ≥ 10 σ; a slip removes at least half of the motion, which on these
    // Khepera-scale intervals is a few σ of translation or much more of rotation.
    std::sort(normalized_errors.begin(), normalized_errors.end());
    EXPECT_GT(normalized_errors[normalized_errors.size() / 2], 5.0);
  }
  LaserSimTruth truth;
  SimulateLaserLog(LaserSimOptions(), &truth);
  EXPECT_EQ(std::count(truth.is_outlier.begin(), truth.is_outlier.end(), true), 0);
}

TEST(LaserSimulatorTest, QuantizedRotationsAreMultiplesOfTheTick) {
  for (const double tau : {0.0, 0.5}) {
    LaserSimOptions options = ExactOptions();
    options.speed_time_constant_s = tau;
    options.encoder_ticks_per_rad = 100.0;
    options.record_steps = 4;
    const LaserLog log = SimulateLaserLog(options);
    const auto expect_ticks = [](double rotation) {
      const double ticks = rotation * 100.0;
      EXPECT_NEAR(ticks, std::round(ticks), 1e-6) << rotation;
    };
    for (const LaserInterval& interval : log.intervals) {
      expect_ticks(interval.left_speed * interval.duration_s);
      expect_ticks(interval.right_speed * interval.duration_s);
      for (const WheelStep& step : interval.steps) {
        expect_ticks(step.left_rad);
        expect_ticks(step.right_rad);
      }
    }
    // Without quantization the rotations are not on the grid.
    options.encoder_ticks_per_rad = 0.0;
    const LaserLog fine = SimulateLaserLog(options);
    int off_grid = 0;
    for (const LaserInterval& interval : fine.intervals) {
      const double ticks = interval.left_speed * interval.duration_s * 100.0;
      if (std::abs(ticks - std::round(ticks)) > 1e-3) ++off_grid;
    }
    EXPECT_GT(off_grid, 900);
  }
}

// Lateral slip, constant speeds: the robot also moves sideways by γ·v·ω·T (robot-frame y).
TEST(LaserSimulatorTest, LateralSlipMovesTheRobotSideways) {
  LaserSimOptions options = ExactOptions();
  options.effects.lateral_slip_s = 0.2;
  LaserSimTruth truth;
  const LaserLog log = SimulateLaserLog(options, &truth);
  const OdometryParams& p = truth.odometry;
  double largest = 0.0;
  for (const LaserInterval& interval : log.intervals) {
    const Pose2d actual = RobotMotion(truth.base_T_sensor, interval.sensor_motion);
    const Pose2d base =
        IntervalRobotMotion(p.left_radius_m, p.right_radius_m, p.wheelbase_m, interval);
    const double v = Forward(p, interval.left_speed, interval.right_speed);
    const double omega = Angular(p, interval.left_speed, interval.right_speed);
    const double sideways = 0.2 * v * omega * interval.duration_s;
    const double turn = std::abs(omega * interval.duration_s);
    // Exactly (−(1 − cos θ)/θ, sin θ/θ)·γvωT, θ = ωT.
    EXPECT_NEAR(actual(1) - base(1), sideways, turn * turn / 6.0 * std::abs(sideways) + 1e-15);
    EXPECT_NEAR(actual(0) - base(0), 0.0, 0.5 * turn * std::abs(sideways) + 1e-15);
    EXPECT_NEAR(actual(2), base(2), 1e-14);
    largest = std::max(largest, std::abs(sideways));
  }
  EXPECT_GT(largest, 1e-5);  // The effect is far above numerical noise.
}

// Longitudinal slip, constant speeds on a straight path: speed jumps are impulses of −γ·Δv,
// half of each seen by the intervals on either side.
TEST(LaserSimulatorTest, LongitudinalSlipWithConstantSpeedsIsAnImpulse) {
  LaserSimOptions options = ExactOptions();
  options.trajectory = LaserTrajectory::kStraight;
  options.effects.longitudinal_slip_s = 0.3;
  LaserSimTruth truth;
  const LaserLog log = SimulateLaserLog(options, &truth);
  const OdometryParams& p = truth.odometry;
  const auto forward = [&](const LaserInterval& interval) {
    return Forward(p, interval.left_speed, interval.right_speed);
  };
  int changes = 0;
  for (size_t k = 1; k + 1 < log.intervals.size(); ++k) {
    const LaserInterval& interval = log.intervals[k];
    const Pose2d actual = RobotMotion(truth.base_T_sensor, interval.sensor_motion);
    const Pose2d base =
        IntervalRobotMotion(p.left_radius_m, p.right_radius_m, p.wheelbase_m, interval);
    const double jump_before = forward(interval) - forward(log.intervals[k - 1]);
    const double jump_after = forward(log.intervals[k + 1]) - forward(interval);
    const double expected = -0.3 * 0.5 * (jump_before + jump_after);
    // The second half-impulse points along the heading at the end, turned by |ωT| < 1e-3.
    EXPECT_NEAR(actual(0) - base(0), expected,
                1e-6 * 0.3 * (std::abs(jump_before) + std::abs(jump_after)) + 1e-15)
        << k;
    if (std::abs(expected) > 1e-4) ++changes;
  }
  EXPECT_GT(changes, 50);
}

// Longitudinal slip, smooth speeds: over an interval the robot falls behind by γ·(v(t_{k+1}) −
// v(t_k)); the end speeds are extrapolated from the means of the first and last three steps.
TEST(LaserSimulatorTest, LongitudinalSlipWithSmoothSpeedsLagsTheAcceleration) {
  LaserSimOptions options;
  options.trajectory = LaserTrajectory::kStraight;
  options.scan_noise_sigma.setZero();
  options.num_intervals = 500;
  options.record_steps = 1000;
  const LaserLog clean = SimulateLaserLog(options);
  options.effects.longitudinal_slip_s = 0.3;
  LaserSimTruth truth;
  const LaserLog log = SimulateLaserLog(options, &truth);
  const OdometryParams& p = truth.odometry;
  const auto step_speed = [&](const WheelStep& step) {
    return Forward(p, step.left_rad, step.right_rad) / step.duration_s;
  };
  // The value at a cell edge from the means of the three cells next to it: (11, −7, 2)/6.
  const auto edge = [](double a, double b, double c) { return (11.0 * a - 7.0 * b + 2.0 * c) / 6; };
  double largest = 0.0;
  double worst = 0.0;
  int close = 0;
  for (size_t k = 0; k < log.intervals.size(); ++k) {
    const std::vector<WheelStep>& s = log.intervals[k].steps;
    const size_t m = s.size();
    const double v_start = edge(step_speed(s[0]), step_speed(s[1]), step_speed(s[2]));
    const double v_end = edge(step_speed(s[m - 1]), step_speed(s[m - 2]), step_speed(s[m - 3]));
    const Pose2d actual = RobotMotion(truth.base_T_sensor, log.intervals[k].sensor_motion);
    const Pose2d without = RobotMotion(truth.base_T_sensor, clean.intervals[k].sensor_motion);
    const double expected = -0.3 * (v_end - v_start);
    const double error = std::abs(actual(0) - without(0) - expected);
    // A new target inside the first or last steps bends the speed there; elsewhere it is smooth.
    if (error < 1e-5 * std::abs(expected) + 1e-10) ++close;
    worst = std::max(worst, error);
    EXPECT_NEAR(actual(2), without(2), 1e-14);
    largest = std::max(largest, std::abs(expected));
  }
  EXPECT_GT(largest, 1e-3);
  EXPECT_GT(close, 490);
  EXPECT_LT(worst, 1e-5 * largest);
}

// The continuous model (u = v − γ_long·dv/dt, w = γ_lat·v·ω) integrated over fine constant-speed
// steps: each step is the exact exponential of its twist, and the longitudinal slip adds
// −γ_long·(v(t_{j+1}) − v(t_j)) with edge speeds interpolated from the step means.
Pose2d FineStepModel(const OdometryParams& p, const std::vector<WheelStep>& steps, double lateral,
                     double longitudinal) {
  const size_t m = steps.size();
  std::vector<double> v(m);
  std::vector<double> omega(m);
  for (size_t j = 0; j < m; ++j) {
    v[j] = Forward(p, steps[j].left_rad, steps[j].right_rad) / steps[j].duration_s;
    omega[j] = Angular(p, steps[j].left_rad, steps[j].right_rad) / steps[j].duration_s;
  }
  std::vector<double> edge(m + 1);
  edge[0] = (11.0 * v[0] - 7.0 * v[1] + 2.0 * v[2]) / 6.0;
  edge[m] = (11.0 * v[m - 1] - 7.0 * v[m - 2] + 2.0 * v[m - 3]) / 6.0;
  for (size_t j = 1; j < m; ++j) edge[j] = 0.5 * (v[j - 1] + v[j]);
  Pose2d motion = Pose2d::Zero();
  for (size_t j = 0; j < m; ++j) {
    const double h = steps[j].duration_s;
    const double along = v[j] * h - longitudinal * (edge[j + 1] - edge[j]);
    const double across = lateral * v[j] * omega[j] * h;
    const Pose2d unit = ArcDisplacement(1.0, omega[j] * h);
    motion = Compose(motion, Pose2d(unit(0) * along - unit(1) * across,
                                    unit(1) * along + unit(0) * across, unit(2)));
  }
  return motion;
}

TEST(LaserSimulatorTest, SmoothEffectsMatchAFineStepIntegration) {
  LaserSimOptions options;
  options.scan_noise_sigma.setZero();
  options.num_intervals = 300;
  options.record_steps = 400;
  options.effects.lateral_slip_s = 0.2;
  options.effects.longitudinal_slip_s = 0.3;
  LaserSimTruth truth;
  const LaserLog log = SimulateLaserLog(options, &truth);
  const OdometryParams& p = truth.odometry;
  double max_error = 0.0;
  double max_effect = 0.0;
  for (const LaserInterval& interval : log.intervals) {
    const Pose2d actual = RobotMotion(truth.base_T_sensor, interval.sensor_motion);
    max_error = std::max(max_error, PoseError(actual, FineStepModel(p, interval.steps, 0.2, 0.3)));
    max_effect = std::max(max_effect, PoseError(actual, FineStepModel(p, interval.steps, 0, 0)));
  }
  EXPECT_LT(max_error, 1e-8);
  EXPECT_GT(max_effect, 1e-3);
}

// Time offset: sm is the base model evaluated on the window shifted by δ.
TEST(LaserSimulatorTest, TimeOffsetShiftsTheScanWindow) {
  for (const double offset : {0.3, -0.3}) {
    LaserSimOptions options = ExactOptions();
    options.effects.time_offset_s = offset;
    LaserSimTruth truth;
    const LaserLog log = SimulateLaserLog(options, &truth);
    const OdometryParams& p = truth.odometry;
    double max_error = 0.0;
    double max_unshifted = 0.0;
    for (size_t k = 1; k + 1 < log.intervals.size(); ++k) {
      const LaserInterval& interval = log.intervals[k];
      const Pose2d robot = offset > 0.0 ? Compose(Arc(p, interval, interval.duration_s - offset),
                                                  Arc(p, log.intervals[k + 1], offset))
                                        : Compose(Arc(p, log.intervals[k - 1], -offset),
                                                  Arc(p, interval, interval.duration_s + offset));
      const Pose2d expected = SensorMotionFromRobotMotion(truth.base_T_sensor, robot);
      max_error = std::max(max_error, PoseError(interval.sensor_motion, expected));
      max_unshifted =
          std::max(max_unshifted,
                   PoseError(interval.sensor_motion, BaseModel(p, truth.base_T_sensor, interval)));
    }
    EXPECT_LT(max_error, 1e-12) << offset;
    EXPECT_GT(max_unshifted, 1e-3) << offset;
  }
}

TEST(LaserSimulatorTest, TimeOffsetWithSmoothSpeedsShiftsTheMotion) {
  // Shifting by a whole number of intervals (no jitter) re-labels the same scans.
  LaserSimOptions options;
  options.scan_noise_sigma.setZero();
  options.interval_jitter_s = 0.0;
  options.mean_interval_s = 0.5;
  options.num_intervals = 300;
  const LaserLog plain = SimulateLaserLog(options);
  for (const int shift : {2, -2}) {
    options.effects.time_offset_s = shift * options.mean_interval_s;
    const LaserLog shifted = SimulateLaserLog(options);
    for (int k = std::max(0, -shift); k + std::max(0, shift) < 300; ++k) {
      EXPECT_LT(
          PoseError(shifted.intervals[k].sensor_motion, plain.intervals[k + shift].sensor_motion),
          1e-12)
          << shift << " " << k;
    }
  }
  // Far before the first target the speeds are that target's: finite, turning at a steady rate.
  options.effects.time_offset_s = -2000.0;
  const LaserLog early = SimulateLaserLog(options);
  for (const LaserInterval& interval : early.intervals) {
    EXPECT_TRUE(interval.sensor_motion.allFinite());
  }
}

TEST(LaserSimulatorTest, RadiusChangeSwitchesTheRadii) {
  LaserSimOptions options = ExactOptions();
  options.effects.radius_change_time_s = 400.0;
  options.effects.left_radius_after_m = 0.0195;
  options.effects.right_radius_after_m = 0.0212;
  LaserSimTruth truth;
  const LaserLog log = SimulateLaserLog(options, &truth);
  const OdometryParams after{0.0195, 0.0212, truth.odometry.wheelbase_m};
  int before_count = 0;
  int after_count = 0;
  for (const LaserInterval& interval : log.intervals) {
    const Pose2d old_model = BaseModel(truth.odometry, truth.base_T_sensor, interval);
    const Pose2d new_model = BaseModel(after, truth.base_T_sensor, interval);
    if (interval.start_s + interval.duration_s <= 400.0) {
      EXPECT_LT(PoseError(interval.sensor_motion, old_model), 1e-12);
      ++before_count;
    } else if (interval.start_s >= 400.0) {
      EXPECT_LT(PoseError(interval.sensor_motion, new_model), 1e-12);
      EXPECT_GT(PoseError(interval.sensor_motion, old_model), 1e-8);
      ++after_count;
    }
  }
  EXPECT_GT(before_count, 400);
  EXPECT_GT(after_count, 400);
  EXPECT_EQ(truth.effects.radius_change_time_s, 400.0);
}

TEST(LaserSimulatorTest, TrajectoryKinds) {
  for (const double tau : {0.0, 0.5}) {
    LaserSimOptions options = ExactOptions();
    options.speed_time_constant_s = tau;
    const OdometryParams& p = options.odometry;
    const double max_speed = options.max_wheel_speed;

    options.trajectory = LaserTrajectory::kStraight;
    for (const LaserInterval& interval : SimulateLaserLog(options).intervals) {
      EXPECT_NEAR(interval.left_speed, interval.right_speed, 1e-12);
      // ω·T ≈ 0: only the radius mismatch turns the robot.
      const double bound = std::abs(p.right_radius_m - p.left_radius_m) * max_speed *
                           interval.duration_s / p.wheelbase_m;
      EXPECT_LE(std::abs(interval.sensor_motion(2)), bound + 1e-12);
    }

    options.trajectory = LaserTrajectory::kPureRotation;
    double largest_turn = 0.0;
    for (const LaserInterval& interval : SimulateLaserLog(options).intervals) {
      EXPECT_NEAR(interval.left_speed, -interval.right_speed, 1e-12);
      const double v = Forward(p, interval.left_speed, interval.right_speed);
      EXPECT_LE(std::abs(v),
                0.5 * std::abs(p.right_radius_m - p.left_radius_m) * max_speed + 1e-12);
      largest_turn = std::max(largest_turn, std::abs(interval.sensor_motion(2)));
    }
    EXPECT_GT(largest_turn, 0.1);

    options.trajectory = LaserTrajectory::kConstantArc;
    for (const LaserInterval& interval : SimulateLaserLog(options).intervals) {
      EXPECT_NEAR(interval.left_speed, 0.3 * max_speed / 0.5, 1e-12);
      EXPECT_NEAR(interval.right_speed, max_speed, 1e-12);
    }

    // Rich: straight runs, rotations and arcs, forward and backward, in similar shares.
    options.trajectory = LaserTrajectory::kRich;
    options.num_intervals = 20000;
    int straight = 0;
    int rotation = 0;
    int arc = 0;
    int backward = 0;
    for (const LaserInterval& interval : SimulateLaserLog(options).intervals) {
      EXPECT_LE(std::max(std::abs(interval.left_speed), std::abs(interval.right_speed)),
                max_speed + 1e-12);
      if (std::abs(interval.left_speed - interval.right_speed) < 1e-9) {
        ++straight;
      } else if (std::abs(interval.left_speed + interval.right_speed) < 1e-9) {
        ++rotation;
      } else {
        ++arc;
      }
      if (interval.left_speed + interval.right_speed < 0.0) ++backward;
    }
    if (tau == 0.0) {
      // Smooth speeds blend consecutive targets, so only constant speeds show pure kinds.
      EXPECT_GT(straight, 4000);
      EXPECT_GT(rotation, 4000);
    }
    EXPECT_GT(arc, 4000);
    EXPECT_GT(backward, 4000);
  }
}

TEST(LaserSimulatorTest, DeterministicForASeed) {
  LaserSimOptions options;
  options.outlier_fraction = 0.05;
  options.record_steps = 3;
  options.encoder_ticks_per_rad = 1000.0;
  options.wheel_speed_noise = 0.001;
  const LaserLog a = SimulateLaserLog(options);
  const LaserLog b = SimulateLaserLog(options);
  ASSERT_EQ(a.intervals.size(), b.intervals.size());
  for (size_t k = 0; k < a.intervals.size(); ++k) {
    EXPECT_EQ(a.intervals[k].start_s, b.intervals[k].start_s);
    EXPECT_EQ(a.intervals[k].left_speed, b.intervals[k].left_speed);
    EXPECT_EQ(a.intervals[k].right_speed, b.intervals[k].right_speed);
    EXPECT_EQ(a.intervals[k].sensor_motion, b.intervals[k].sensor_motion);
    EXPECT_EQ(a.intervals[k].steps.back().left_rad, b.intervals[k].steps.back().left_rad);
  }
  options.seed = 2;
  const LaserLog c = SimulateLaserLog(options);
  int different = 0;
  for (size_t k = 0; k < a.intervals.size(); ++k) {
    if (a.intervals[k].sensor_motion != c.intervals[k].sensor_motion) ++different;
  }
  EXPECT_EQ(different, static_cast<int>(a.intervals.size()));
}

TEST(LaserSimulatorTest, StreamsMatchTheLog) {
  LaserSimOptions options = ExactOptions();
  options.effects.time_offset_s = 0.1;
  const double rate = 50.0;
  LaserSimTruth truth;
  const LaserStreams streams = SimulateLaserStreams(options, rate, &truth);
  const LaserLog log = SimulateLaserLog(options);
  ASSERT_EQ(streams.sensor_poses.size(), log.intervals.size() + 1);
  EXPECT_EQ(truth.is_outlier.size(), log.intervals.size());
  const double end = log.intervals.back().start_s + log.intervals.back().duration_s;
  ASSERT_GE(streams.odometry.size(), 2u);
  EXPECT_EQ(streams.odometry.front().t_s, 0.0);
  EXPECT_GE(streams.odometry.back().t_s, end);
  EXPECT_LT(streams.odometry.back().t_s, end + 1.0 / rate + 1e-9);
  // Samples evenly spaced; between samples inside one interval the wheels turn at its speeds.
  size_t k = 0;
  int checked = 0;
  for (size_t j = 1; j < streams.odometry.size(); ++j) {
    const EncoderSample& a = streams.odometry[j - 1];
    const EncoderSample& b = streams.odometry[j];
    ASSERT_NEAR(b.t_s - a.t_s, 1.0 / rate, 1e-9);
    while (k + 1 < log.intervals.size() && log.intervals[k + 1].start_s <= a.t_s) ++k;
    const LaserInterval& interval = log.intervals[k];
    if (b.t_s <= interval.start_s + interval.duration_s) {
      EXPECT_NEAR((b.left_rad - a.left_rad) / (b.t_s - a.t_s), interval.left_speed, 1e-9);
      EXPECT_NEAR((b.right_rad - a.right_rad) / (b.t_s - a.t_s), interval.right_speed, 1e-9);
      ++checked;
    }
  }
  EXPECT_GT(checked, 30000);
  // Poses: one per interval boundary, their displacements are the log's sm.
  for (size_t i = 0; i < log.intervals.size(); ++i) {
    EXPECT_EQ(streams.sensor_poses[i].t_s, log.intervals[i].start_s);
    const Pose2d displacement =
        Between(streams.sensor_poses[i].world_T_sensor, streams.sensor_poses[i + 1].world_T_sensor);
    EXPECT_LT(PoseError(displacement, log.intervals[i].sensor_motion), 1e-9) << i;
  }
  EXPECT_LT(PoseError(streams.sensor_poses[0].world_T_sensor, truth.base_T_sensor), 1e-15);
}

TEST(LaserSimulatorTest, StreamPoseNoiseIsPerPose) {
  LaserSimOptions options;
  options.num_intervals = 20000;
  const Eigen::Vector3d sigma = options.scan_noise_sigma;
  const LaserStreams noisy = SimulateLaserStreams(options, 0.0);
  options.scan_noise_sigma.setZero();
  const LaserStreams clean = SimulateLaserStreams(options, 0.0);
  EXPECT_EQ(noisy.odometry.size(), clean.odometry.size());
  EXPECT_EQ(noisy.odometry.size(), 20001u);  // Rate 0: samples at the interval boundaries.
  std::vector<Pose2d> errors;
  for (size_t k = 0; k + 1 < noisy.sensor_poses.size(); ++k) {
    const Pose2d measured =
        Between(noisy.sensor_poses[k].world_T_sensor, noisy.sensor_poses[k + 1].world_T_sensor);
    const Pose2d actual =
        Between(clean.sensor_poses[k].world_T_sensor, clean.sensor_poses[k + 1].world_T_sensor);
    Pose2d error = measured - actual;
    error(2) = WrapAngle(error(2));
    errors.push_back(error);
  }
  for (int j = 0; j < 3; ++j) {
    double squares = 0.0;
    double lagged = 0.0;
    for (size_t k = 0; k < errors.size(); ++k) {
      squares += errors[k](j) * errors[k](j);
      if (k > 0) lagged += errors[k](j) * errors[k - 1](j);
    }
    const double std = std::sqrt(squares / errors.size());
    // Displacement noise ≈ σ per component, consecutive ones correlated by about −1/2.
    EXPECT_NEAR(std, sigma(j), 0.1 * sigma(j)) << j;
    EXPECT_NEAR(lagged / squares, -0.5, 0.05) << j;
  }
}

TEST(LaserSimulatorTest, StreamOutliersCorruptOnlyTheirDisplacement) {
  LaserSimOptions options;
  options.scan_noise_sigma.setZero();
  options.outlier_fraction = 0.1;
  LaserSimTruth truth;
  const LaserStreams streams = SimulateLaserStreams(options, 10.0, &truth);
  const LaserLog log = SimulateLaserLog(options);
  for (size_t k = 0; k < log.intervals.size(); ++k) {
    const Pose2d displacement =
        Between(streams.sensor_poses[k].world_T_sensor, streams.sensor_poses[k + 1].world_T_sensor);
    EXPECT_LT(PoseError(displacement, log.intervals[k].sensor_motion), 1e-9) << k;
  }
  EXPECT_EQ(std::count(truth.is_outlier.begin(), truth.is_outlier.end(), true), 100);
}

TEST(LaserSimulatorTest, DropBackwardIntervalsMarksGaps) {
  LaserSimOptions sim;
  sim.num_intervals = 400;
  const LaserLog log = SimulateLaserLog(sim);
  const std::vector<LaserInterval> kept = DropBackwardIntervals(log.intervals, sim.odometry);
  ASSERT_FALSE(kept.empty());
  ASSERT_LT(kept.size(), log.intervals.size());  // The rich trajectory drives both ways.
  EXPECT_FALSE(kept.front().gap_before);
  size_t k = 0;  // Walk the original log alongside the kept intervals.
  bool dropped = false;
  for (const LaserInterval& interval : kept) {
    while (log.intervals[k].record != interval.record) {
      dropped = true;
      ++k;
    }
    EXPECT_GE(sim.odometry.left_radius_m * interval.left_speed +
                  sim.odometry.right_radius_m * interval.right_speed,
              -1e-9);
    EXPECT_EQ(interval.gap_before, dropped && &interval != &kept.front());
    dropped = false;
    ++k;
  }
}

}  // namespace
}  // namespace calib
