#include <calib/core/bag/robot_bag.h>
#include <calib/core/bag/robot_messages.h>
#include <calib/core/bag/ros1_decoder.h>
#include <calib/core/text_file.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

namespace calib {
namespace {

using nlohmann::json;

const std::string kBags = std::string(CALIB_SOURCE_DIR) + "/data/bags/";
const char* const kCompressions[] = {"none", "bz2", "lz4"};

std::string BagPath(const std::string& compression) {
  return kBags + "small_robot_" + compression + ".bag";
}

const json& Doc() {
  static const json doc = [] {
    std::string text;
    EXPECT_TRUE(ReadWholeFile(kBags + "small_robot_ros1.json", &text).ok());
    return json::parse(text);
  }();
  return doc;
}

// The JSON's messages of one topic, with their index in the bag (the write order), sorted by
// log time as the reader returns them.
std::vector<std::pair<int64_t, const json*>> Expected(const std::string& topic) {
  std::vector<std::pair<int64_t, const json*>> out;
  const json& messages = Doc()["messages"];
  for (size_t i = 0; i < messages.size(); ++i) {
    if (messages[i]["topic"] == topic) out.emplace_back(i, &messages[i]);
  }
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return (*a.second)["log_time_ns"].template get<int64_t>() <
           (*b.second)["log_time_ns"].template get<int64_t>();
  });
  return out;
}

// The double the reader makes of a ROS time: seconds + nanoseconds · 1e-9, both exact.
double Seconds(const json& stamp) {
  return stamp["sec"].get<uint32_t>() + stamp["nanosec"].get<uint32_t>() * 1e-9;
}
double LogSeconds(const json& m) {
  const int64_t ns = m["log_time_ns"].get<int64_t>();
  return static_cast<uint32_t>(ns / 1000000000) + static_cast<uint32_t>(ns % 1000000000) * 1e-9;
}
double Number(const json& v) {
  return v.is_string() ? std::stod(v.get<std::string>()) : v.get<double>();
}

void ExpectSameFloat(float expected, float actual, const std::string& what) {
  if (std::isnan(expected)) {
    EXPECT_TRUE(std::isnan(actual)) << what;
  } else {
    EXPECT_EQ(expected, actual) << what;  // Also ±inf.
  }
}

RobotMessages MustRead(const std::string& path, const BagReadOptions& options = {}) {
  auto bag = ReadRos1Bag(path, options);
  EXPECT_TRUE(bag.ok()) << bag.message();
  return bag.ok() ? std::move(bag).value() : RobotMessages{};
}

class Ros1FixtureTest : public ::testing::TestWithParam<const char*> {};

TEST_P(Ros1FixtureTest, TopicsTypesAndCounts) {
  const RobotMessages bag = MustRead(BagPath(GetParam()));
  EXPECT_EQ(bag.source, BagPath(GetParam()));
  std::map<std::string, std::pair<std::string, int64_t>> expected;
  for (const json& t : Doc()["topics"]) expected[t["name"]] = {t["type"], 0};
  for (const json& m : Doc()["messages"]) ++expected[m["topic"]].second;
  ASSERT_EQ(bag.topics.size(), expected.size());
  for (const TopicInfo& t : bag.topics) {
    ASSERT_TRUE(expected.count(t.name)) << t.name;
    EXPECT_EQ(t.type, expected[t.name].first) << t.name;
    EXPECT_EQ(t.message_count, expected[t.name].second) << t.name;
  }
  EXPECT_EQ(expected["/scan"].second, 20);
  EXPECT_EQ(expected["/joint_states"].second, 40);
}

TEST_P(Ros1FixtureTest, ScansAreTheJsonValues) {
  const RobotMessages bag = MustRead(BagPath(GetParam()));
  const auto expected = Expected("/scan");
  ASSERT_EQ(bag.scans.size(), 1u);
  const std::vector<LaserScan>& scans = bag.scans.at("/scan");
  ASSERT_EQ(scans.size(), expected.size());
  int nan = 0, inf = 0;
  for (size_t k = 0; k < scans.size(); ++k) {
    const LaserScan& s = scans[k];
    const json& m = (*expected[k].second)["msg"];
    EXPECT_EQ(s.record, expected[k].first);
    EXPECT_EQ(s.log_time_s, LogSeconds(*expected[k].second));
    EXPECT_EQ(s.stamp_s, Seconds(m["header"]["stamp"]));
    EXPECT_EQ(s.frame_id, m["header"]["frame_id"]);
    EXPECT_EQ(s.angle_min_rad, static_cast<float>(m["angle_min"].get<double>()));
    EXPECT_EQ(s.angle_increment_rad, static_cast<float>(m["angle_increment"].get<double>()));
    EXPECT_EQ(s.time_increment_s, static_cast<float>(m["time_increment"].get<double>()));
    EXPECT_EQ(s.scan_time_s, static_cast<float>(m["scan_time"].get<double>()));
    EXPECT_EQ(s.range_min_m, static_cast<float>(m["range_min"].get<double>()));
    EXPECT_EQ(s.range_max_m, static_cast<float>(m["range_max"].get<double>()));
    ASSERT_EQ(s.ranges_m.size(), m["ranges"].size());
    ASSERT_EQ(s.intensities.size(), m["intensities"].size());
    for (size_t i = 0; i < s.ranges_m.size(); ++i) {
      const float r = static_cast<float>(Number(m["ranges"][i]));
      ExpectSameFloat(r, s.ranges_m[i], "scan " + std::to_string(k) + " beam " + std::to_string(i));
      nan += std::isnan(s.ranges_m[i]);
      inf += std::isinf(s.ranges_m[i]);
      EXPECT_EQ(s.intensities[i], static_cast<float>(Number(m["intensities"][i])));
    }
  }
  EXPECT_EQ(nan, 20);
  EXPECT_EQ(inf, 30);  // +inf in every scan, -inf in every other.
}

TEST_P(Ros1FixtureTest, JointStatesOdometryAndTfAreTheJsonValues) {
  const RobotMessages bag = MustRead(BagPath(GetParam()));
  const auto joints = Expected("/joint_states");
  const std::vector<JointState>& js = bag.joint_states.at("/joint_states");
  ASSERT_EQ(js.size(), joints.size());
  for (size_t k = 0; k < js.size(); ++k) {
    const json& m = (*joints[k].second)["msg"];
    EXPECT_EQ(js[k].record, joints[k].first);
    EXPECT_EQ(js[k].log_time_s, LogSeconds(*joints[k].second));
    EXPECT_EQ(js[k].stamp_s, Seconds(m["header"]["stamp"]));
    EXPECT_EQ(js[k].name, m["name"].get<std::vector<std::string>>());
    EXPECT_EQ(js[k].position, m["position"].get<std::vector<double>>());
    EXPECT_EQ(js[k].velocity, m["velocity"].get<std::vector<double>>());
    EXPECT_TRUE(js[k].effort.empty());
  }
  EXPECT_EQ(js[0].name.size(), 3u);  // The caster joint in some messages.
  EXPECT_EQ(js[1].name.size(), 2u);

  const auto odom = Expected("/odom");
  const std::vector<Odometry>& od = bag.odometry.at("/odom");
  ASSERT_EQ(od.size(), odom.size());
  for (size_t k = 0; k < od.size(); ++k) {
    const json& m = (*odom[k].second)["msg"];
    const json& pose = m["pose"]["pose"];
    const json& twist = m["twist"]["twist"];
    EXPECT_EQ(od[k].record, odom[k].first);
    EXPECT_EQ(od[k].stamp_s, Seconds(m["header"]["stamp"]));
    EXPECT_EQ(od[k].frame_id, "odom");
    EXPECT_EQ(od[k].child_frame_id, "base_link");
    EXPECT_EQ(od[k].position.x(), pose["position"]["x"].get<double>());
    EXPECT_EQ(od[k].position.y(), pose["position"]["y"].get<double>());
    EXPECT_EQ(od[k].orientation.z(), pose["orientation"]["z"].get<double>());
    EXPECT_EQ(od[k].orientation.w(), pose["orientation"]["w"].get<double>());
    EXPECT_EQ(od[k].linear_velocity.x(), twist["linear"]["x"].get<double>());
    EXPECT_EQ(od[k].angular_velocity.z(), twist["angular"]["z"].get<double>());
  }

  ASSERT_EQ(bag.tf_static.size(), 1u);
  const TransformStamped& s = bag.tf_static[0];
  EXPECT_EQ(s.parent_frame, "base_link");
  EXPECT_EQ(s.child_frame, "laser");
  EXPECT_EQ(s.translation, Eigen::Vector3d(0.12, -0.03, 0.25));
  EXPECT_EQ(s.rotation.z(), std::sin(0.05 / 2));
  EXPECT_EQ(s.record, 0);
  const auto tf = Expected("/tf");
  ASSERT_EQ(bag.tf.size(), tf.size());
  for (size_t k = 0; k < tf.size(); ++k) {
    const json& t = (*tf[k].second)["msg"]["transforms"][0];
    EXPECT_EQ(bag.tf[k].record, tf[k].first);
    EXPECT_EQ(bag.tf[k].stamp_s, Seconds(t["header"]["stamp"]));
    EXPECT_EQ(bag.tf[k].parent_frame, "odom");
    EXPECT_EQ(bag.tf[k].child_frame, "base_link");
    EXPECT_EQ(bag.tf[k].translation.x(), t["transform"]["translation"]["x"].get<double>());
    EXPECT_EQ(bag.tf[k].rotation.w(), t["transform"]["rotation"]["w"].get<double>());
  }
}

TEST_P(Ros1FixtureTest, MessagesAreInLogTimeOrderNotFileOrder) {
  const RobotMessages bag = MustRead(BagPath(GetParam()));
  const std::vector<LaserScan>& scans = bag.scans.at("/scan");
  bool file_order = true;
  for (size_t k = 1; k < scans.size(); ++k) {
    EXPECT_LE(scans[k - 1].log_time_s, scans[k].log_time_s);
    file_order = file_order && scans[k - 1].record < scans[k].record;
  }
  EXPECT_FALSE(file_order);  // One scan was received late in the fixture.
}

TEST_P(Ros1FixtureTest, TopicsOptionDecodesOnlyThose) {
  BagReadOptions options;
  options.topics = {"/scan", "/tf_static"};
  const RobotMessages only = MustRead(BagPath(GetParam()), options);
  const RobotMessages all = MustRead(BagPath(GetParam()));
  EXPECT_EQ(only.topics.size(), all.topics.size());  // Every topic listed all the same.
  EXPECT_TRUE(only.joint_states.empty());
  EXPECT_TRUE(only.odometry.empty());
  EXPECT_TRUE(only.tf.empty());
  EXPECT_EQ(only.tf_static.size(), 1u);
  ASSERT_EQ(only.scans.at("/scan").size(), 20u);
  for (size_t k = 0; k < 20; ++k) {
    EXPECT_EQ(only.scans.at("/scan")[k].record, all.scans.at("/scan")[k].record);
  }
}

INSTANTIATE_TEST_SUITE_P(Compressions, Ros1FixtureTest, ::testing::ValuesIn(kCompressions));

void ExpectSame(const RobotMessages& a, const RobotMessages& b) {
  ASSERT_EQ(a.topics.size(), b.topics.size());
  for (size_t i = 0; i < a.topics.size(); ++i) {
    EXPECT_EQ(a.topics[i].name, b.topics[i].name);
    EXPECT_EQ(a.topics[i].message_count, b.topics[i].message_count);
  }
  const auto& sa = a.scans.at("/scan");
  const auto& sb = b.scans.at("/scan");
  ASSERT_EQ(sa.size(), sb.size());
  for (size_t k = 0; k < sa.size(); ++k) {
    EXPECT_EQ(sa[k].record, sb[k].record);
    EXPECT_EQ(sa[k].stamp_s, sb[k].stamp_s);
    ASSERT_EQ(sa[k].ranges_m.size(), sb[k].ranges_m.size());
    EXPECT_EQ(0, std::memcmp(sa[k].ranges_m.data(), sb[k].ranges_m.data(),
                             sa[k].ranges_m.size() * sizeof(float)));
  }
  const auto& ja = a.joint_states.at("/joint_states");
  const auto& jb = b.joint_states.at("/joint_states");
  ASSERT_EQ(ja.size(), jb.size());
  for (size_t k = 0; k < ja.size(); ++k) {
    EXPECT_EQ(ja[k].name, jb[k].name);
    EXPECT_EQ(ja[k].position, jb[k].position);
    EXPECT_EQ(ja[k].log_time_s, jb[k].log_time_s);
  }
  ASSERT_EQ(a.odometry.at("/odom").size(), b.odometry.at("/odom").size());
  EXPECT_EQ(a.tf.size(), b.tf.size());
  EXPECT_EQ(a.tf_static.size(), b.tf_static.size());
}

TEST(Ros1BagTest, TheThreeCompressionsAgree) {
  const RobotMessages none = MustRead(BagPath("none"));
  ExpectSame(none, MustRead(BagPath("bz2")));
  ExpectSame(none, MustRead(BagPath("lz4")));
}

std::string Bytes(const std::string& path) {
  std::string bytes;
  EXPECT_TRUE(ReadWholeFile(path, &bytes).ok());
  return bytes;
}

std::string WriteTemp(const std::string& name, const std::string& bytes) {
  const std::string path = std::string(CALIB_BINARY_DIR) + "/tests/rosbag1_" + name + ".bag";
  EXPECT_TRUE(WriteWholeFile(path, bytes).ok());
  return path;
}

uint64_t IndexPos(const std::string& bytes) {
  const size_t at = bytes.find("index_pos=");
  uint64_t pos = 0;
  std::memcpy(&pos, bytes.data() + at + 10, 8);
  return pos;
}

// The bag as an interrupted recording leaves it: no index section, index_pos 0.
std::string WithoutIndex(std::string bytes) {
  const uint64_t index_pos = IndexPos(bytes);
  bytes.resize(index_pos);
  for (const char* field : {"index_pos=", "conn_count=", "chunk_count="}) {
    const size_t at = bytes.find(field) + std::strlen(field);
    std::memset(&bytes[at], 0, std::string(field) == "index_pos=" ? 8 : 4);
  }
  return bytes;
}

TEST(Ros1BagTest, ABagWithoutIndexReadsTheSame) {
  for (const char* c : kCompressions) {
    const std::string path =
        WriteTemp(std::string("noindex_") + c, WithoutIndex(Bytes(BagPath(c))));
    SCOPED_TRACE(path);
    ExpectSame(MustRead(BagPath(c)), MustRead(path));
  }
}

void ExpectError(const std::string& path, const std::vector<std::string>& words) {
  const auto bag = ReadRos1Bag(path);
  ASSERT_FALSE(bag.ok()) << path;
  EXPECT_EQ(bag.code(), StatusCode::kInvalidInput) << bag.message();
  EXPECT_NE(bag.message().find(path), std::string::npos) << bag.message();
  for (const std::string& w : words) {
    EXPECT_NE(bag.message().find(w), std::string::npos) << "'" << w << "' in: " << bag.message();
  }
}

TEST(Ros1BagTest, TruncatedBagsNameTheByte) {
  for (const char* c : kCompressions) {
    const std::string bytes = Bytes(BagPath(c));
    const uint64_t index_pos = IndexPos(bytes);
    for (const uint64_t size : {uint64_t{20}, uint64_t{4000}, uint64_t{4200}, index_pos / 2,
                                index_pos - 3, index_pos + 3, index_pos + 40, bytes.size() - 1}) {
      const std::string path = WriteTemp("cut", bytes.substr(0, size));
      SCOPED_TRACE(std::string(c) + " cut at " + std::to_string(size));
      ExpectError(path, {"truncated", "byte"});
    }
    ExpectError(WriteTemp("short", bytes.substr(0, 7)), {"not a ROS bag"});
    // Without the index, a cut in a chunk is found by the scan.
    const std::string unindexed = WithoutIndex(bytes);
    for (const uint64_t size : {uint64_t{4200}, index_pos / 2, index_pos - 3}) {
      ExpectError(WriteTemp("cut", unindexed.substr(0, size)), {"truncated", "byte"});
    }
  }
}

// Cuts one copy shorter and shorter (no rewriting), every 53 bytes.
template <typename Check>
void CutEverywhere(const std::string& bytes, Check check) {
  const std::string path = WriteTemp("cut_anywhere", bytes);
  for (size_t size = bytes.size() - 1 - (bytes.size() - 1) % 53;; size -= 53) {
    std::filesystem::resize_file(path, size);
    check(ReadRos1Bag(path), size);
    if (size < 53) break;
  }
}

TEST(Ros1BagTest, ACutAnywhereInAnIndexedBagIsAnError) {
  for (const char* c : kCompressions) {
    const std::string bytes = Bytes(BagPath(c));
    CutEverywhere(bytes, [&](const StatusOr<RobotMessages>& bag, size_t size) {
      EXPECT_FALSE(bag.ok()) << c << " cut at " << size;
    });
    // Without the index a cut between two records leaves a shorter bag: it need only not crash.
    CutEverywhere(WithoutIndex(bytes), [](const StatusOr<RobotMessages>&, size_t) {});
  }
}

TEST(Ros1BagTest, BadMagicAndVersion) {
  std::string bytes = Bytes(BagPath("none"));
  bytes[1] = 'X';
  ExpectError(WriteTemp("magic", bytes), {"not a ROS bag", "#ROSBAG V2.0"});
  bytes[1] = 'R';
  bytes.replace(9, 3, "1.2");
  ExpectError(WriteTemp("version", bytes), {"unsupported ROS bag version '1.2'"});
  // A bag of ROS's first format (before 2010) is told apart as one, with the way to convert it.
  const std::string old = WriteTemp("old", "#ROSRECORD V1.2\n" + bytes.substr(13));
  const StatusOr<RobotMessages> read = ReadRobotBag(old);
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.message().find("unsupported ROS bag version '1.2'"), std::string::npos)
      << read.message();
  EXPECT_NE(read.message().find("rosbag fix"), std::string::npos) << read.message();
  const auto missing = ReadRos1Bag(kBags + "no_such.bag");
  EXPECT_EQ(missing.code(), StatusCode::kIo);
  EXPECT_NE(missing.message().find("no such file"), std::string::npos);
}

TEST(Ros1BagTest, UnknownCompressionIsNamed) {
  std::string bytes = Bytes(BagPath("bz2"));
  for (size_t at = bytes.find("compression=bz2"); at != std::string::npos;
       at = bytes.find("compression=bz2", at)) {
    bytes.replace(at + 12, 3, "zst");
  }
  ExpectError(WriteTemp("compression", bytes), {"chunk at byte", "unknown compression 'zst'"});
}

TEST(Ros1BagTest, AMessageShorterThanItsFieldsNamesTopicAndRecord) {
  std::string bytes = Bytes(BagPath("none"));
  // The first LaserScan: header (seq, stamp, "laser"), 7 floats, then the ranges' count, 31.
  const std::string frame("\x05\x00\x00\x00laser", 9);
  size_t at = 0;
  for (at = bytes.find(frame); at != std::string::npos; at = bytes.find(frame, at + 1)) {
    if (static_cast<unsigned char>(bytes[at + 9 + 28]) == 31) break;
  }
  ASSERT_NE(at, std::string::npos);
  bytes[at + 9 + 28] = static_cast<char>(200);            // 200 beams claimed, 31 present.
  const int64_t first_scan = Expected("/scan")[0].first;  // Its index in the bag.
  ExpectError(WriteTemp("short_msg", bytes),
              {"topic '/scan'", "message " + std::to_string(first_scan), "sensor_msgs/LaserScan",
               "shorter than its fields", "'ranges'"});
}

TEST(Ros1DecoderTest, LengthsAreBoundedAndTrailingBytesRejected) {
  std::string msg(4 + 8 + 4, '\0');  // seq, stamp, empty frame_id: nothing more.
  LaserScan scan;
  Status s = ros1::DecodeLaserScan(msg, &scan);
  EXPECT_NE(s.message().find("'angle_min'"), std::string::npos) << s.message();
  JointState joints;
  std::string names = msg + std::string("\xff\xff\xff\x7f", 4);  // 2^31 names claimed.
  s = ros1::DecodeJointState(names, &joints);
  EXPECT_NE(s.message().find("'name'"), std::string::npos) << s.message();
  std::vector<TransformStamped> tf;
  s = ros1::DecodeTfMessage(std::string("\x00\x00\x00\x00\x01", 5), &tf);
  EXPECT_NE(s.message().find("bytes left after the last field"), std::string::npos) << s.message();
  EXPECT_TRUE(ros1::DecodeTfMessage(std::string(4, '\0'), &tf).ok());
}

TEST(Ros1BagTest, CorruptBytesNeverCrash) {
  std::mt19937 rng(7);
  int failed = 0, runs = 0;
  const char* more = std::getenv("CALIB_ROSBAG1_FUZZ_TRIALS");  // For longer runs by hand.
  const int trials = more != nullptr ? std::atoi(more) : 100;
  for (const char* c : kCompressions) {
    const std::string bytes = Bytes(BagPath(c));
    for (int trial = 0; trial < trials; ++trial, ++runs) {
      std::string copy = bytes;
      const int flips = 1 + trial % 4;
      for (int f = 0; f < flips; ++f) {
        copy[rng() % copy.size()] = static_cast<char>(rng());
      }
      const std::string path = WriteTemp("fuzz", copy);
      const auto bag = ReadRos1Bag(path);
      failed += !bag.ok();
      if (!bag.ok()) {
        EXPECT_EQ(bag.message().rfind(path + ": ", 0), 0u) << bag.message();
      }
    }
  }
  EXPECT_GT(failed, 0);
  EXPECT_LE(failed, runs);
}

// The read speed on a large bag (write_rosbag1.py --large PATH), a study run by hand:
// CALIB_ROSBAG1_LARGE=PATH rosbag1_reader_test --gtest_also_run_disabled_tests
//     --gtest_filter='*LargeBag*'
TEST(Ros1BagTest, DISABLED_LargeBagReadSpeed) {
  const char* path = std::getenv("CALIB_ROSBAG1_LARGE");
  ASSERT_NE(path, nullptr) << "set CALIB_ROSBAG1_LARGE to a large bag to time it";
  const auto start = std::chrono::steady_clock::now();
  const auto bag = ReadRos1Bag(path);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(bag.ok()) << bag.message();
  size_t scans = 0, beams = 0;
  for (const auto& [topic, v] : bag->scans) {
    scans += v.size();
    for (const LaserScan& s : v) beams += s.ranges_m.size();
  }
  std::printf("read %zu scans, %zu beams in %.3f s\n", scans, beams, seconds);
  RecordProperty("read_seconds", std::to_string(seconds));
}

}  // namespace
}  // namespace calib
