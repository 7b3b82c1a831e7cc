#include <calib/core/whitening.h>
#include <calib/problems/laser/laser_residual.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>

namespace calib {
namespace {

constexpr double kRl = 0.0206, kRr = 0.0207, kB = 0.088;
const Pose2d kMounting(-0.005, 0.006, -1.55);

LaserInterval ExactInterval(double left_speed, double right_speed, double duration) {
  LaserInterval interval;
  interval.duration_s = duration;
  interval.left_speed = left_speed;
  interval.right_speed = right_speed;
  interval.sensor_motion =
      SensorMotionFromRobotMotion(kMounting, IntervalRobotMotion(kRl, kRr, kB, interval));
  return interval;
}

TEST(LaserResidualTest, ZeroAtTruth) {
  const Eigen::Matrix3d sqrt_information = Eigen::Vector3d(1e3, 2e3, 5e2).asDiagonal();
  const double odometry[3] = {kRl, kRr, kB};
  const double mounting[3] = {kMounting(0), kMounting(1), kMounting(2)};
  for (const auto& speeds : {Eigen::Vector2d(0.5, 0.5), Eigen::Vector2d(0.5, -0.5),
                             Eigen::Vector2d(0.1, 0.4), Eigen::Vector2d(-0.3, -0.2)}) {
    const LaserInterval interval = ExactInterval(speeds(0), speeds(1), 0.8);
    double residual[3] = {NAN, NAN, NAN};
    ASSERT_TRUE(LaserResidual(interval, &sqrt_information)(odometry, mounting, residual));
    for (double r : residual) EXPECT_NEAR(r, 0.0, 1e-12);
  }
}

TEST(LaserResidualTest, AngleIsWrapped) {
  // A measured rotation just below π and a predicted one just above it differ by a small angle.
  LaserInterval interval = ExactInterval(-2.0, 2.0, 0.8);
  const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
  const double odometry[3] = {kRl, kRr, kB};
  const double mounting[3] = {kMounting(0), kMounting(1), kMounting(2)};
  interval.sensor_motion(2) += 2 * M_PI;
  double residual[3];
  LaserResidual(interval, &identity)(odometry, mounting, residual);
  EXPECT_NEAR(residual[2], 0.0, 1e-12);
}

TEST(LaserResidualTest, SqrtInformationSquaresToInformation) {
  Eigen::Matrix3d covariance;
  covariance << 4e-6, 1e-6, 2e-7, 1e-6, 2e-6, -1e-7, 2e-7, -1e-7, 1e-5;
  const Eigen::Matrix3d l = SqrtInformation<3>(covariance);
  EXPECT_TRUE((l.transpose() * l).isApprox(covariance.inverse(), 1e-10));
  EXPECT_NEAR(l(1, 0), 0.0, 0.0);  // Upper triangular.
  EXPECT_NEAR(l(2, 0), 0.0, 0.0);
  EXPECT_NEAR(l(2, 1), 0.0, 0.0);
}

TEST(LaserResidualTest, JacobiansMatchCentralDifferences) {
  const Eigen::Matrix3d sqrt_information = Eigen::Vector3d(1e3, 1e3, 5e2).asDiagonal();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> speed(-0.6, 0.6);
  for (int trial = 0; trial < 20; ++trial) {
    LaserInterval interval = ExactInterval(speed(rng), speed(rng), 0.8);
    if (trial % 2) {  // Also through the stepped (non-constant speed) model.
      interval.steps = {{0.3, 0.1, 0.2}, {0.5, -0.05, 0.3}};
    }
    interval.sensor_motion += Eigen::Vector3d(1e-3, -2e-3, 3e-3);
    std::unique_ptr<ceres::CostFunction> cost(LaserResidual::Create(interval, &sqrt_information));
    double odometry[3] = {0.021, 0.020, 0.09};
    double mounting[3] = {0.01, -0.02, 0.3 * trial};
    double* parameters[2] = {odometry, mounting};
    double residual[3];
    double jacobian_odometry[9], jacobian_mounting[9];
    std::fill_n(jacobian_odometry, 9, std::numeric_limits<double>::quiet_NaN());
    std::fill_n(jacobian_mounting, 9, std::numeric_limits<double>::quiet_NaN());
    double* jacobians[2] = {jacobian_odometry, jacobian_mounting};
    ASSERT_TRUE(cost->Evaluate(parameters, residual, jacobians));
    for (int block = 0; block < 2; ++block) {
      for (int j = 0; j < 3; ++j) {
        const double h = 1e-7;
        double* p = parameters[block];
        const double saved = p[j];
        double plus[3], minus[3];
        p[j] = saved + h;
        cost->Evaluate(parameters, plus, nullptr);
        p[j] = saved - h;
        cost->Evaluate(parameters, minus, nullptr);
        p[j] = saved;
        for (int i = 0; i < 3; ++i) {
          const double numeric = (plus[i] - minus[i]) / (2 * h);
          const double analytic = jacobians[block][i * 3 + j];  // Row-major.
          EXPECT_NEAR(analytic, numeric, 1e-5 * std::max(1.0, std::abs(numeric)))
              << "block " << block << " parameter " << j << " residual " << i;
        }
      }
    }
  }
}

// The closed-form linearization of a constant-speed interval equals the automatic
// differentiation of operator() (Ceres' cost function), also at a straight run (turn angle 0),
// below the series cut-off, near a half turn, and with a full whitening matrix.
TEST(LaserResidualTest, ConstantSpeedLinearizationEqualsAutomaticDifferentiation) {
  Eigen::Matrix3d sqrt_information;
  sqrt_information << 1e3, 2e2, -1e2, 0.0, 1.5e3, 3e1, 0.0, 0.0, 4e2;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> speed(-3.0, 3.0);
  std::vector<Eigen::Vector2d> speeds = {
      {0.5, 0.5}, {0.5, 0.5 + 1e-4}, {-2.0, 2.0}, {0.0, 0.0}, {-4.2, 4.4}};
  for (int i = 0; i < 40; ++i) speeds.emplace_back(speed(rng), speed(rng));
  for (size_t trial = 0; trial < speeds.size(); ++trial) {
    LaserInterval interval = ExactInterval(speeds[trial](0), speeds[trial](1), 0.8);
    interval.sensor_motion += Eigen::Vector3d(1e-3, -2e-3, 3e-3);
    const double odometry[3] = {0.021, 0.020, 0.09};
    const double mounting[3] = {0.01, -0.02, -3.0 + 0.15 * trial};
    std::unique_ptr<ceres::CostFunction> cost(LaserResidual::Create(interval, &sqrt_information));
    const double* parameters[2] = {odometry, mounting};
    Eigen::Vector3d expected_residual;
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> by_odometry, by_mounting;
    double* jacobians[2] = {by_odometry.data(), by_mounting.data()};
    ASSERT_TRUE(cost->Evaluate(parameters, expected_residual.data(), jacobians));
    Eigen::Vector3d residual = Eigen::Vector3d::Constant(std::nan(""));
    Eigen::Matrix<double, 3, 6> jacobian = Eigen::Matrix<double, 3, 6>::Constant(std::nan(""));
    LaserResidual::Linearize(interval, sqrt_information, odometry, mounting, &residual, &jacobian);
    const double scale = jacobian.cwiseAbs().maxCoeff();
    EXPECT_LT((residual - expected_residual).norm(), 1e-12 * (1.0 + expected_residual.norm()))
        << "trial " << trial;
    EXPECT_LT((jacobian.leftCols<3>() - by_odometry).cwiseAbs().maxCoeff(), 1e-11 * scale + 1e-300)
        << "trial " << trial;
    EXPECT_LT((jacobian.rightCols<3>() - by_mounting).cwiseAbs().maxCoeff(), 1e-11 * scale + 1e-300)
        << "trial " << trial;
    // The value-only closed form, whitened and not.
    Eigen::Vector3d evaluated = Eigen::Vector3d::Constant(std::nan(""));
    LaserResidual::Evaluate(interval, sqrt_information, odometry, mounting, &evaluated);
    EXPECT_LT((evaluated - expected_residual).norm(), 1e-12 * (1.0 + expected_residual.norm()));
    const Eigen::Matrix3d identity = Eigen::Matrix3d::Identity();
    Eigen::Vector3d plain;
    LaserResidual(interval, &identity)(odometry, mounting, plain.data());
    EXPECT_LT((LaserResidual::Error(interval, odometry, mounting) - plain).norm(),
              1e-12 * (1.0 + plain.norm()));
  }
}

}  // namespace
}  // namespace calib
