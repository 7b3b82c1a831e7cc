#include <calib/core/bag/tf_tree.h>
#include <gtest/gtest.h>

namespace calib {
namespace {

TransformStamped Transform(const std::string& parent, const std::string& child, double x, double y,
                           double z, const Eigen::Quaterniond& q) {
  TransformStamped t;
  t.parent_frame = parent;
  t.child_frame = child;
  t.translation = Eigen::Vector3d(x, y, z);
  t.rotation = q;
  return t;
}

Eigen::Quaterniond Yaw(double yaw) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
}

TEST(TfTree, MountingChainsThroughIntermediateFrames) {
  RobotMessages bag;
  bag.tf_static = {Transform("base_footprint", "base_link", 0, 0, 0.01, Yaw(0)),
                   Transform("/base_link", "laser_mount", 0.1, 0.02, 0.2, Yaw(0.5)),
                   Transform("laser_mount", "laser", 0.05, 0.0, 0.0, Yaw(-0.2))};
  bag.tf = {Transform("odom", "base_footprint", 3, 4, 0, Yaw(1))};
  const StatusOr<PlanarMounting> m = MountingFromTf(bag, "base_link", "laser");
  ASSERT_TRUE(m.ok()) << m.message();
  EXPECT_NEAR(m->base_T_sensor(0), 0.1 + 0.05 * std::cos(0.5), 1e-12);
  EXPECT_NEAR(m->base_T_sensor(1), 0.02 + 0.05 * std::sin(0.5), 1e-12);
  EXPECT_NEAR(m->base_T_sensor(2), 0.3, 1e-12);
  EXPECT_FALSE(m->upside_down);
  EXPECT_EQ(m->chain, "base_link → laser_mount → laser");
  // From the footprint, through its child.
  const StatusOr<PlanarMounting> f = MountingFromTf(bag, "base_footprint", "laser");
  ASSERT_TRUE(f.ok()) << f.message();
  EXPECT_NEAR(f->base_T_sensor(2), 0.3, 1e-12);
}

TEST(TfTree, AnUpsideDownSensorIsFlaggedAndUnconnectedFramesNamed) {
  RobotMessages bag;
  bag.source = "run.bag";
  const Eigen::Quaterniond flipped(Eigen::AngleAxisd(3.14159265358979, Eigen::Vector3d::UnitX()));
  bag.tf_static = {Transform("base_link", "laser", 0.1, 0, 0.2, flipped)};
  const StatusOr<PlanarMounting> m = MountingFromTf(bag, "base_link", "laser");
  ASSERT_TRUE(m.ok()) << m.message();
  EXPECT_TRUE(m->upside_down);
  EXPECT_NEAR(m->tilt_rad, 3.14159265358979, 1e-9);
  const StatusOr<PlanarMounting> none = MountingFromTf(bag, "base_link", "camera");
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.message().find("'camera'"), std::string::npos) << none.message();
}

}  // namespace
}  // namespace calib
