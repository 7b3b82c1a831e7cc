#include <calib/core/bag/wheel_angles.h>
#include <calib/core/diff_drive.h>
#include <calib/core/se2.h>
#include <gtest/gtest.h>

#include <cmath>

namespace calib {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(WheelAngles, JointStatesAreUnwrappedAndOtherJointsSkipped) {
  std::vector<JointState> messages;
  for (int k = 0; k < 100; ++k) {
    JointState j;
    j.stamp_s = 0.1 * k;
    j.record = k;
    j.name = {"right_wheel", "left_wheel"};
    const double left = 0.9 * k, right = -0.5 * k;  // Up to 89 rad: many turns.
    j.position = {std::remainder(right, 2 * kPi), std::remainder(left, 2 * kPi)};
    messages.push_back(j);
    if (k % 10 == 0) {
      JointState other;
      other.name = {"caster"};
      other.position = {0.0};
      messages.push_back(other);
    }
  }
  const StatusOr<WheelAngleStream> s =
      WheelAnglesFromJointStates(messages, "left_wheel", "right_wheel", "run.mcap /joint_states");
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(s->samples.size(), 100u);
  EXPECT_EQ(s->skipped_messages, 10);
  EXPECT_GT(s->unwrapped_turns, 10);
  const double left0 = s->samples[0].left_rad;
  for (int k = 0; k < 100; ++k) {
    EXPECT_NEAR(s->samples[k].left_rad - left0, 0.9 * k, 1e-9);
    EXPECT_NEAR(s->samples[k].right_rad, -0.5 * k, 1e-9);
    EXPECT_EQ(s->samples[k].line, k);
  }
}

TEST(WheelAngles, JointStateErrorsNameTheRecord) {
  JointState j;
  j.record = 7;
  j.name = {"l", "r"};
  j.position = {0.0};
  StatusOr<WheelAngleStream> s = WheelAnglesFromJointStates({j, j}, "l", "r", "run.bag /js");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("run.bag /js: record 7"), std::string::npos) << s.message();
  j.name = {"l"};
  s = WheelAnglesFromJointStates({j, j}, "l", "r", "run.bag /js");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("carry one of them"), std::string::npos) << s.message();
}

// A driver that publishes only the wheels' speeds: the angles are their trapezoid integrals (exact
// for speeds linear in time); positions after speeds are refused, naming the record.
TEST(WheelAngles, JointStateVelocitiesAreIntegratedWhenThereAreNoPositions) {
  std::vector<JointState> messages;
  for (int k = 0; k < 50; ++k) {
    JointState j;
    j.stamp_s = 0.02 * k + (k % 3 == 0 ? 0.004 : 0.0);  // Jittered stamps.
    j.record = k;
    j.name = {"left_wheel", "right_wheel"};
    j.velocity = {2.0 + 3.0 * j.stamp_s, -1.0};
    messages.push_back(j);
  }
  const StatusOr<WheelAngleStream> s =
      WheelAnglesFromJointStates(messages, "left_wheel", "right_wheel", "run.db3 /joint_states");
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_TRUE(s->from_velocities);
  ASSERT_EQ(s->samples.size(), 50u);
  const double t0 = messages[0].stamp_s;
  for (const EncoderSample& e : s->samples) {
    const double dt = e.t_s - t0;
    EXPECT_NEAR(e.left_rad, 2.0 * dt + 1.5 * (e.t_s * e.t_s - t0 * t0), 1e-12);
    EXPECT_NEAR(e.right_rad, -dt, 1e-12);
  }
  messages[20].position = {1.0, 2.0};
  messages[20].velocity.clear();
  const StatusOr<WheelAngleStream> mixed =
      WheelAnglesFromJointStates(messages, "left_wheel", "right_wheel", "run.db3 /joint_states");
  ASSERT_FALSE(mixed.ok());
  EXPECT_NE(mixed.message().find("record 20: JointState carries positions where the messages "
                                 "before it carried velocities only"),
            std::string::npos)
      << mixed.message();
}

// A driver's odometry integrated with radius r and wheelbase b: the angles come back exactly.
TEST(WheelAngles, OdometryPosesGiveTheNominalWheelAngles) {
  const double r = 0.033, b = 0.16;
  std::vector<Odometry> messages;
  Pose2d pose = Pose2d::Zero();
  double left = 0.0, right = 0.0;
  std::vector<std::pair<double, double>> truth;
  for (int k = 0; k < 200; ++k) {
    if (k > 0) {
      const double dl = 0.3 * std::sin(0.05 * k) + (k > 100 ? -0.2 : 0.25);
      const double dr = 0.3 * std::cos(0.07 * k) + 0.1;
      left += dl, right += dr;
      pose = Compose(pose, WheelStepDisplacement(r, r, b, dl, dr));
    }
    truth.push_back({left, right});
    Odometry o;
    o.stamp_s = 0.05 * k;
    o.record = k;
    o.position = Eigen::Vector3d(pose(0), pose(1), 0.0);
    o.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(pose(2), Eigen::Vector3d::UnitZ()));
    messages.push_back(o);
  }
  const StatusOr<WheelAngleStream> s = WheelAnglesFromOdometry(messages, r, b, "run.mcap /odom");
  ASSERT_TRUE(s.ok()) << s.message();
  for (int k = 0; k < 200; ++k) {
    EXPECT_NEAR(s->samples[k].left_rad, truth[k].first, 1e-8) << k;
    EXPECT_NEAR(s->samples[k].right_rad, truth[k].second, 1e-8) << k;
  }
  EXPECT_FALSE(WheelAnglesFromOdometry(messages, 0.0, b, "run.mcap /odom").ok());
}

TEST(WheelAngles, OdometryTwistWhenThePosesAreEmpty) {
  std::vector<Odometry> messages(11);
  for (int k = 0; k <= 10; ++k) {
    messages[k].stamp_s = 0.1 * k;
    messages[k].linear_velocity.x() = 0.2;
    messages[k].angular_velocity.z() = 0.5;
  }
  const StatusOr<WheelAngleStream> s = WheelAnglesFromOdometry(messages, 0.05, 0.2, "odom");
  ASSERT_TRUE(s.ok()) << s.message();
  // 1 s of v = 0.2 m/s, ω = 0.5 rad/s: (0.2 ∓ 0.05)/0.05 rad.
  EXPECT_NEAR(s->samples.back().left_rad, 3.0, 1e-12);
  EXPECT_NEAR(s->samples.back().right_rad, 5.0, 1e-12);
}

}  // namespace
}  // namespace calib
