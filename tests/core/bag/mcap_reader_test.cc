#include <calib/core/bag/cdr_decoder.h>
#include <calib/core/bag/robot_messages.h>
#include <calib/core/text_file.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <vector>

#include "tests/core/bag/small_robot_expectations.h"
#include "tests/scratch_dir.h"

namespace calib {
namespace {

using testing::kBags;
const std::vector<std::string> kFixtures = {"small_robot_zstd.mcap", "small_robot_lz4.mcap",
                                            "small_robot_none.mcap", "small_robot_nosummary.mcap"};

class FixtureTest : public ::testing::TestWithParam<std::string> {};

TEST_P(FixtureTest, DecodesExactlyTheMessagesTheReferenceWriterWasGiven) {
  const auto bag = ReadMcapBag(kBags + GetParam());
  ASSERT_TRUE(bag.ok()) << bag.message();
  EXPECT_EQ(kBags + GetParam(), bag->source);
  testing::ExpectSmallRobot(*bag);
}

TEST_P(FixtureTest, ListsEveryTopicWithItsTypeAndCount) {
  const auto bag = ReadMcapBag(kBags + GetParam());
  ASSERT_TRUE(bag.ok()) << bag.message();
  testing::ExpectSmallRobotTopics(*bag);
}

TEST_P(FixtureTest, DecodesOnlyTheRequestedTopicsAndIgnoresUnknownOnes) {
  BagReadOptions options;
  options.topics = {"/scan", "/tf_static", "/no_such_topic"};
  const auto bag = ReadMcapBag(kBags + GetParam(), options);
  ASSERT_TRUE(bag.ok()) << bag.message();
  ASSERT_EQ(1u, bag->scans.size());
  EXPECT_EQ(20u, bag->scans.at("/scan").size());
  EXPECT_TRUE(bag->joint_states.empty());
  EXPECT_TRUE(bag->odometry.empty());
  EXPECT_TRUE(bag->tf.empty());
  EXPECT_EQ(1u, bag->tf_static.size());
  EXPECT_EQ(5u, bag->topics.size());  // Counted all the same.
  testing::ExpectScans(testing::Input(), bag->scans.at("/scan"));
}

INSTANTIATE_TEST_SUITE_P(Fixtures, FixtureTest, ::testing::ValuesIn(kFixtures),
                         [](const auto& info) {
                           return info.param.substr(12, info.param.size() - 17);
                         });

TEST(McapReaderTest, ScansComeInLogTimeOrderNotFileOrder) {
  const auto bag = ReadMcapBag(kBags + "small_robot_zstd.mcap");
  ASSERT_TRUE(bag.ok()) << bag.message();
  const auto& scans = bag->scans.at("/scan");
  bool out_of_file_order = false;
  for (size_t i = 1; i < scans.size(); ++i) {
    EXPECT_LE(scans[i - 1].log_time_s, scans[i].log_time_s);
    out_of_file_order = out_of_file_order || scans[i - 1].record > scans[i].record;
  }
  EXPECT_TRUE(out_of_file_order);  // The input swaps two scans.
}

TEST(McapReaderTest, FixturesAgreeBitForBit) {
  const auto reference = ReadMcapBag(kBags + kFixtures[0]);
  ASSERT_TRUE(reference.ok()) << reference.message();
  for (size_t f = 1; f < kFixtures.size(); ++f) {
    const auto bag = ReadMcapBag(kBags + kFixtures[f]);
    ASSERT_TRUE(bag.ok()) << bag.message();
    const auto& a = reference->scans.at("/scan");
    const auto& b = bag->scans.at("/scan");
    ASSERT_EQ(a.size(), b.size());
    for (size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].record, b[i].record);
      ASSERT_EQ(a[i].ranges_m.size(), b[i].ranges_m.size());
      EXPECT_EQ(0, std::memcmp(a[i].ranges_m.data(), b[i].ranges_m.data(),
                               a[i].ranges_m.size() * sizeof(float)))
          << kFixtures[f] << " scan " << i;
    }
  }
}

std::string Fixture(const std::string& name) {
  std::string bytes;
  EXPECT_TRUE(ReadWholeFile(kBags + name, &bytes).ok());
  return bytes;
}

// This test's folder for altered copies, made on first use and removed at exit.
const std::filesystem::path& ScratchFolder() {
  static const testing::ScratchDir dir("mcap_reader_test_");
  return dir.path();
}

std::string Scratch(const std::string& name, const std::string& bytes) {
  const std::string path = (ScratchFolder() / name).string();
  EXPECT_TRUE(WriteWholeFile(path, bytes).ok());
  return path;
}

TEST(McapReaderTest, ChunkedFileWithoutSummaryIsScannedLinearly) {
  std::string bytes = Fixture("small_robot_zstd.mcap");
  // Footer: opcode, length, summary_start u64, ... then the 8 magic bytes.
  const size_t summary_start = bytes.size() - 8 - 20;
  std::memset(&bytes[summary_start], 0, 16);
  const auto bag = ReadMcapBag(Scratch("no_summary_start.mcap", bytes));
  ASSERT_TRUE(bag.ok()) << bag.message();
  const nlohmann::json input = testing::Input();
  testing::ExpectScans(input, bag->scans.at("/scan"));
  testing::ExpectJoints(input, bag->joint_states.at("/joint_states"));
  EXPECT_EQ(40, bag->topics[2].message_count);
}

// The chunk indexes let a reader skip chunks that hold none of the wanted topics: a corrupt last
// chunk goes unnoticed when only /tf_static (in the first chunk) is asked for.
TEST(McapReaderTest, IndexedReadSkipsChunksWithoutWantedTopics) {
  std::string bytes = Fixture("small_robot_zstd.mcap");
  std::vector<size_t> chunks;
  for (size_t at = 8; at + 9 <= bytes.size() && bytes[at] != 0x0F;) {  // Up to Data End.
    uint64_t length = 0;
    std::memcpy(&length, &bytes[at + 1], 8);
    if (bytes[at] == 0x06) chunks.push_back(at);
    at += 9 + length;
  }
  ASSERT_GE(chunks.size(), 3u);
  for (size_t i = chunks.back() + 200; i < chunks.back() + 220; ++i) bytes[i] ^= 0x5a;
  const std::string path = Scratch("corrupt_last_chunk.mcap", bytes);
  BagReadOptions options;
  options.topics = {"/tf_static"};
  const auto bag = ReadMcapBag(path, options);
  ASSERT_TRUE(bag.ok()) << bag.message();
  EXPECT_EQ(1u, bag->tf_static.size());
  EXPECT_EQ(40, bag->topics[1].message_count);
  const auto all = ReadMcapBag(path);
  ASSERT_FALSE(all.ok());
  EXPECT_NE(std::string::npos,
            all.message().find("Chunk record at byte " + std::to_string(chunks.back())))
      << all.message();
}

TEST(McapReaderTest, ReadsABagDirectory) {
  const testing::ScratchDir scratch("mcap_reader_test_bag_dir_");
  const std::string dir = scratch.path().string();
  ASSERT_TRUE(WriteWholeFile(dir + "/metadata.yaml", "rosbag2_bagfile_information:\n").ok());
  const auto empty = ReadMcapBag(dir);
  ASSERT_FALSE(empty.ok());
  EXPECT_NE(std::string::npos, empty.message().find("holds no .mcap file")) << empty.message();
  ASSERT_TRUE(WriteWholeFile(dir + "/run_0.mcap", Fixture("small_robot_lz4.mcap")).ok());
  const auto bag = ReadMcapBag(dir);
  ASSERT_TRUE(bag.ok()) << bag.message();
  EXPECT_EQ(dir + "/run_0.mcap", bag->source);
  EXPECT_EQ(40u, bag->odometry.at("/odom").size());
}

// A bag rosbag2 split into three files (written by @mcap/core): the same messages as the
// single file, each topic in log-time order, records numbered on across the files.
TEST(McapReaderTest, ReadsASplitBagDirectory) {
  const auto split = ReadMcapBag(kBags + "sim_robot_split");
  ASSERT_TRUE(split.ok()) << split.message();
  const auto single = ReadMcapBag(kBags + "sim_robot_zstd.mcap");
  ASSERT_TRUE(single.ok()) << single.message();
  ASSERT_EQ(single->topics.size(), split->topics.size());
  for (size_t i = 0; i < single->topics.size(); ++i) {
    EXPECT_EQ(single->topics[i].name, split->topics[i].name);
    EXPECT_EQ(single->topics[i].message_count, split->topics[i].message_count);
  }
  const std::vector<LaserScan>& a = single->scans.at("/scan");
  const std::vector<LaserScan>& b = split->scans.at("/scan");
  ASSERT_EQ(a.size(), b.size());
  std::set<int64_t> records;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].stamp_s, b[i].stamp_s);
    EXPECT_EQ(a[i].ranges_m, b[i].ranges_m);
    records.insert(b[i].record);
  }
  EXPECT_EQ(records.size(), b.size());
  EXPECT_EQ(single->joint_states.at("/joint_states").size(),
            split->joint_states.at("/joint_states").size());
  EXPECT_EQ(single->tf_static.size(), split->tf_static.size());
}

TEST(McapReaderTest, MissingFileIsAnIoError) {
  const auto bag = ReadMcapBag(kBags + "no_such.mcap");
  ASSERT_FALSE(bag.ok());
  EXPECT_EQ(StatusCode::kIo, bag.code());
  EXPECT_NE(std::string::npos, bag.message().find("no_such.mcap: no such file")) << bag.message();
}

TEST(McapReaderTest, BadMagicIsNotAnMcapFile) {
  std::string bytes = Fixture("small_robot_zstd.mcap");
  bytes[1] = 'X';
  const auto bag = ReadMcapBag(Scratch("bad_magic.mcap", bytes));
  ASSERT_FALSE(bag.ok());
  EXPECT_NE(std::string::npos, bag.message().find("not an MCAP file")) << bag.message();
  const auto json = ReadMcapBag(kBags + "small_robot.json");
  ASSERT_FALSE(json.ok());
  EXPECT_NE(std::string::npos, json.message().find("not an MCAP file")) << json.message();
}

TEST(McapReaderTest, TruncatedFilesFailNamingTheByte) {
  for (const std::string& name : kFixtures) {
    const std::string bytes = Fixture(name);
    const std::string path = (ScratchFolder() / "truncated.mcap").string();
    std::vector<size_t> cuts = {0, 5, 8, 9, 16, bytes.size() - 9, bytes.size() - 1};
    for (size_t cut = 17; cut < bytes.size(); cut += 211) cuts.push_back(cut);
    for (size_t cut : cuts) {
      ASSERT_TRUE(WriteWholeFile(path, bytes.substr(0, cut)).ok());
      const auto bag = ReadMcapBag(path);
      ASSERT_FALSE(bag.ok()) << name << " cut at " << cut;
      const std::string& m = bag.message();
      EXPECT_EQ(0u, m.find(path)) << m;
      if (cut < 8) {
        EXPECT_NE(std::string::npos, m.find("not an MCAP file")) << m;
      } else {
        EXPECT_NE(std::string::npos, m.find("truncated")) << name << " cut at " << cut << ": " << m;
        EXPECT_NE(std::string::npos, m.find("at byte ")) << m;
      }
    }
  }
}

void ReplaceAll(std::string* bytes, const std::string& from, const std::string& to) {
  for (size_t at = bytes->find(from); at != std::string::npos; at = bytes->find(from, at + 1)) {
    bytes->replace(at, from.size(), to);
  }
}

TEST(McapReaderTest, UnknownCompressionIsNamed) {
  for (const std::string name : {"small_robot_zstd.mcap", "small_robot_lz4.mcap"}) {
    std::string bytes = Fixture(name);
    const std::string compression = name.find("zstd") != std::string::npos ? "zstd" : "lz4";
    ReplaceAll(&bytes, std::string("\0\0\0", 3) + compression,
               std::string("\0\0\0", 3) + std::string(compression.size(), 'q'));
    const auto bag = ReadMcapBag(Scratch("unknown_compression.mcap", bytes));
    ASSERT_FALSE(bag.ok());
    EXPECT_NE(std::string::npos, bag.message().find("unknown compression '" +
                                                    std::string(compression.size(), 'q') + "'"))
        << bag.message();
    EXPECT_NE(std::string::npos, bag.message().find("Chunk record at byte ")) << bag.message();
  }
}

TEST(McapReaderTest, CorruptChunkDataFailsCleanly) {
  for (const std::string name : {"small_robot_zstd.mcap", "small_robot_lz4.mcap"}) {
    std::string bytes = Fixture(name);
    // Scribble over the middle of the first chunk's compressed records.
    for (size_t i = 300; i < 340; ++i) bytes[i] = static_cast<char>(i * 37);
    const auto bag = ReadMcapBag(Scratch("corrupt_chunk.mcap", bytes));
    ASSERT_FALSE(bag.ok()) << name;
    EXPECT_NE(std::string::npos, bag.message().find("Chunk record at byte")) << bag.message();
    EXPECT_NE(std::string::npos, bag.message().find("corrupt")) << bag.message();
  }
}

// Patched in the file without chunks: a chunk's CRC would catch the change.
TEST(McapReaderTest, OtherTypesAreListedButNotDecoded) {
  std::string bytes = Fixture("small_robot_nosummary.mcap");
  ReplaceAll(&bytes, "sensor_msgs/msg/JointState", "sensor_msgs/msg/JointStatf");
  const auto bag = ReadMcapBag(Scratch("other_type.mcap", bytes));
  ASSERT_TRUE(bag.ok()) << bag.message();
  EXPECT_TRUE(bag->joint_states.empty());
  EXPECT_EQ("sensor_msgs/JointStatf", bag->topics[1].type);
  EXPECT_EQ(40, bag->topics[1].message_count);
  EXPECT_EQ(20u, bag->scans.at("/scan").size());
}

TEST(McapReaderTest, CdrSequenceLongerThanTheMessageNamesTopicAndRecord) {
  std::string bytes = Fixture("small_robot_nosummary.mcap");
  // A scan's CDR: header(4) sec nanosec "laser"(4 + 6, padded to 24), 7 floats, then the
  // ranges count (30) at byte 52.
  const std::string laser("\x06\0\0\0laser\0", 10);
  size_t patched = 0;
  for (size_t at = bytes.find(laser); at != std::string::npos && patched == 0;
       at = bytes.find(laser, at + 1)) {
    const size_t count_at = at + 12 + 28;
    if (count_at + 4 <= bytes.size() &&
        bytes.compare(count_at, 4, std::string("\x1e\0\0\0", 4)) == 0) {
      bytes.replace(count_at, 4, std::string("\0\0\0\x7f", 4));
      ++patched;
    }
  }
  ASSERT_EQ(1u, patched);
  const auto bag = ReadMcapBag(Scratch("long_sequence.mcap", bytes));
  ASSERT_FALSE(bag.ok());
  EXPECT_NE(std::string::npos, bag.message().find("topic '/scan' record ")) << bag.message();
  EXPECT_NE(std::string::npos, bag.message().find("'ranges'")) << bag.message();
}

// Bytes of the record framing, the chunks and the summary overwritten in turn: each read ends in
// a result or an error naming the file, never a crash, hang or huge allocation (ASan-clean).
TEST(McapReaderTest, ScribbledBytesNeverCrash) {
  for (const std::string name : {"small_robot_zstd.mcap", "small_robot_nosummary.mcap"}) {
    const std::string original = Fixture(name);
    const std::string path = (ScratchFolder() / "scribbled.mcap").string();
    for (size_t at = 8; at < original.size();
         at += (at < 90 || at + 250 > original.size()) ? 3 : 401) {
      std::string bytes = original;
      bytes[at] = static_cast<char>(~bytes[at]);
      ASSERT_TRUE(WriteWholeFile(path, bytes).ok());
      const auto bag = ReadMcapBag(path);
      if (!bag.ok()) {
        EXPECT_EQ(0u, bag.message().find(path)) << bag.message();
      }
    }
  }
}

// A hand-made CDR stream, little- or big-endian, aligned as XCDR1 from the end of the header.
class Cdr {
 public:
  explicit Cdr(bool little_endian) : little_(little_endian) {
    bytes_ = {0, static_cast<char>(little_endian ? 1 : 0), 0, 0};
  }
  template <typename T>
  Cdr& Put(T value) {
    while ((bytes_.size() - 4) % sizeof(T) != 0) bytes_.push_back(0);
    char raw[sizeof(T)];
    std::memcpy(raw, &value, sizeof(T));
    for (size_t i = 0; i < sizeof(T); ++i) bytes_.push_back(raw[little_ ? i : sizeof(T) - 1 - i]);
    return *this;
  }
  Cdr& Str(const std::string& s) {
    Put<uint32_t>(s.size() + 1);
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    bytes_.push_back(0);
    return *this;
  }
  const uint8_t* data() const { return reinterpret_cast<const uint8_t*>(bytes_.data()); }
  size_t size() const { return bytes_.size(); }

 private:
  bool little_;
  std::string bytes_;
};

Cdr JointStateCdr(bool little_endian) {
  Cdr cdr(little_endian);
  cdr.Put<int32_t>(1700000123).Put<uint32_t>(987654321).Str("base");
  cdr.Put<uint32_t>(2).Str("left_wheel_joint").Str("r");
  cdr.Put<uint32_t>(2).Put(1.25).Put(-2.5);
  cdr.Put<uint32_t>(2).Put(0.125).Put(-0.25);
  cdr.Put<uint32_t>(0);
  return cdr;
}

TEST(CdrDecoderTest, BigAndLittleEndianDecodeAlike) {
  for (bool little : {true, false}) {
    const Cdr cdr = JointStateCdr(little);
    JointState joints;
    ASSERT_TRUE(DecodeJointState(cdr.data(), cdr.size(), &joints).ok());
    EXPECT_EQ(1700000123 + 1e-9 * 987654321, joints.stamp_s);
    EXPECT_EQ("base", joints.frame_id);
    EXPECT_EQ((std::vector<std::string>{"left_wheel_joint", "r"}), joints.name);
    EXPECT_EQ((std::vector<double>{1.25, -2.5}), joints.position);
    EXPECT_EQ((std::vector<double>{0.125, -0.25}), joints.velocity);
    EXPECT_TRUE(joints.effort.empty());
  }
}

TEST(CdrDecoderTest, JointStateArraysAreEmptyOrOnePerName) {
  Cdr cdr(true);
  cdr.Put<int32_t>(1).Put<uint32_t>(2).Str("");
  cdr.Put<uint32_t>(2).Str("left").Str("right");
  cdr.Put<uint32_t>(2).Put(1.0).Put(2.0).Put<uint32_t>(1).Put(3.0).Put<uint32_t>(0);
  JointState joints;
  const Status status = DecodeJointState(cdr.data(), cdr.size(), &joints);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(std::string::npos, status.message().find("'velocity' holds 1 values for 2 names"))
      << status.message();
}

TEST(CdrDecoderTest, EveryShorterMessageFailsNamingAField) {
  const Cdr cdr = JointStateCdr(false);
  for (size_t n = 0; n < cdr.size(); ++n) {
    JointState joints;
    const Status status = DecodeJointState(cdr.data(), n, &joints);
    ASSERT_FALSE(status.ok()) << n;
    EXPECT_NE(std::string::npos, status.message().find("field '")) << status.message();
  }
  Odometry odometry;
  EXPECT_FALSE(DecodeOdometry(cdr.data(), cdr.size(), &odometry).ok());  // Far too short.
  Cdr scan_cdr(true);
  scan_cdr.Put<int32_t>(5).Put<uint32_t>(6).Str("laser");
  for (int i = 0; i < 7; ++i) scan_cdr.Put(0.5f);
  scan_cdr.Put<uint32_t>(2).Put(1.0f).Put(NAN).Put<uint32_t>(0);
  LaserScan scan;
  ASSERT_TRUE(DecodeLaserScan(scan_cdr.data(), scan_cdr.size(), &scan).ok());
  EXPECT_EQ(2u, scan.ranges_m.size());
  EXPECT_TRUE(std::isnan(scan.ranges_m[1]));
  for (size_t n = 0; n < scan_cdr.size(); ++n) {
    const Status status = DecodeLaserScan(scan_cdr.data(), n, &scan);
    ASSERT_FALSE(status.ok()) << n;
    EXPECT_NE(std::string::npos, status.message().find("field '")) << status.message();
  }
}

TEST(CdrDecoderTest, UnsupportedEncapsulationIsNamed) {
  const uint8_t xcdr2[] = {0, 7, 0, 0, 1, 0, 0, 0};
  std::vector<TransformStamped> transforms;
  const Status status = DecodeTfMessage(xcdr2, sizeof(xcdr2), &transforms);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(std::string::npos, status.message().find("encapsulation 0x0007")) << status.message();
}

// Times reading a large bag (scripts/fixtures/write_mcap.mjs --synthetic), a study run by hand:
// CALIB_LARGE_MCAP=/path/big.mcap mcap_reader_test --gtest_also_run_disabled_tests
//     --gtest_filter='*LargeBagTiming'
TEST(McapReaderTest, DISABLED_LargeBagTiming) {
  const char* path = std::getenv("CALIB_LARGE_MCAP");
  ASSERT_NE(path, nullptr) << "set CALIB_LARGE_MCAP to a large .mcap to time it";
  const auto start = std::chrono::steady_clock::now();
  const auto bag = ReadMcapBag(path);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(bag.ok()) << bag.message();
  size_t scans = 0, beams = 0;
  for (const auto& [topic, list] : bag->scans) {
    scans += list.size();
    for (const LaserScan& s : list) beams += s.ranges_m.size();
  }
  std::printf("read %s: %zu scans, %zu beams in %.3f s\n", path, scans, beams, seconds);
}

}  // namespace
}  // namespace calib
