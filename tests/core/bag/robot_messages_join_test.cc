#include <calib/core/bag/robot_messages_join.h>
#include <calib/core/scan/scan_simulator.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace calib {
namespace {

RobotMessages Recording(uint64_t seed) {
  ScanSimOptions o;
  o.laser = DefaultScanLaserOptions();
  o.laser.num_intervals = 100;
  o.laser.seed = o.seed = seed;
  o.beams = 90;
  const StatusOr<ScanSimulation> sim = SimulateScans(o);
  EXPECT_TRUE(sim.ok()) << sim.message();
  return ScanSimulationMessages(*sim);
}

// The messages stamped before `t_s` (first) or from it on (second), as a bag split by duration
// holds them; tf_static in both.
RobotMessages Part(const RobotMessages& m, double t_s, bool first, const std::string& source) {
  RobotMessages out;
  out.source = source;
  out.topics = m.topics;
  const auto keep = [&](const auto& message) { return (message.stamp_s < t_s) == first; };
  for (const auto& [topic, list] : m.scans) {
    for (const auto& x : list)
      if (keep(x)) out.scans[topic].push_back(x);
  }
  for (const auto& [topic, list] : m.joint_states) {
    for (const auto& x : list)
      if (keep(x)) out.joint_states[topic].push_back(x);
  }
  for (const auto& [topic, list] : m.odometry) {
    for (const auto& x : list)
      if (keep(x)) out.odometry[topic].push_back(x);
  }
  for (const auto& x : m.tf)
    if (keep(x)) out.tf.push_back(x);
  out.tf_static = m.tf_static;
  return out;
}

// A bag split in two, given in either order: one recording again, no restart.
TEST(JoinRecordings, ASplitBagIsOneRecordingAgain) {
  const RobotMessages whole = Recording(3);
  const std::vector<LaserScan>& scans = whole.scans.at("/scan");
  const double middle_s = scans[scans.size() / 2].stamp_s;
  const StatusOr<RobotMessages> joined = JoinRecordings(
      {Part(whole, middle_s, false, "run_1.bag"), Part(whole, middle_s, true, "run_0.bag")},
      "run_0.bag,run_1.bag");
  ASSERT_TRUE(joined.ok()) << joined.message();
  EXPECT_TRUE(joined->restarts_s.empty());
  EXPECT_EQ(joined->source, "run_0.bag,run_1.bag");
  ASSERT_EQ(joined->scans.at("/scan").size(), scans.size());
  EXPECT_EQ(joined->scans.at("/scan").back().stamp_s, scans.back().stamp_s);
  const std::vector<JointState>& joints = joined->joint_states.at("/joint_states");
  ASSERT_EQ(joints.size(), whole.joint_states.at("/joint_states").size());
  EXPECT_EQ(joints.back().position, whole.joint_states.at("/joint_states").back().position);
}

// Two runs whose logger started its clock and counters anew: the second starts again 10 s
// after the first, its joints going on from the first's last positions. One run given twice is
// refused.
TEST(JoinRecordings, RunsThatStartAgainAreMarkedAndMoved) {
  const RobotMessages a = Recording(3), b = Recording(4);
  StatusOr<RobotMessages> joined = JoinRecordings({a, b}, "a,b");
  ASSERT_TRUE(joined.ok()) << joined.message();
  const double end_s = a.scans.at("/scan").back().stamp_s;
  ASSERT_EQ(joined->restarts_s.size(), 1u);
  EXPECT_NEAR(joined->restarts_s[0], end_s + 10.0, 1e-9);
  const std::vector<JointState>& joints = joined->joint_states.at("/joint_states");
  const size_t first_b = a.joint_states.at("/joint_states").size();
  EXPECT_EQ(joints[first_b].position, joints[first_b - 1].position);
  EXPECT_GT(joints[first_b].record, joints[first_b - 1].record);

  joined = JoinRecordings({a, a}, "a,a");
  ASSERT_FALSE(joined.ok());
  EXPECT_NE(joined.message().find("hold the same scans: one recording given twice?"),
            std::string::npos);
  RobotMessages other = b;
  other.source = "other.bag";
  other.topics.front().type = "nav_msgs/Odometry";
  joined = JoinRecordings({a, other}, "a,other");
  ASSERT_FALSE(joined.ok());
  EXPECT_NE(joined.message().find("are they one robot's recordings?"), std::string::npos)
      << joined.message();
}

}  // namespace
}  // namespace calib
