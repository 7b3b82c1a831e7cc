#include <calib/core/bag/robot_bag.h>
#include <calib/core/bag/robot_messages.h>
#include <calib/core/text_file.h>
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/core/bag/small_robot_expectations.h"
#include "tests/scratch_dir.h"

namespace calib {
namespace {

namespace fs = std::filesystem;
using testing::kBags;

// small_robot.json as rosbag2 writes it in its sqlite3 storage (write_db3.mjs): Jazzy's schema
// uncompressed, Humble's with each message zstd-compressed, Foxy's with the file compressed.
const std::vector<std::string> kFixtures = {"small_robot_db3", "small_robot_db3_humble_message",
                                            "small_robot_db3_foxy_file"};

class SqliteFixtureTest : public ::testing::TestWithParam<std::string> {};

TEST_P(SqliteFixtureTest, DecodesExactlyTheMessagesTheReferenceWriterWasGiven) {
  const auto bag = ReadSqliteBag(kBags + GetParam());
  ASSERT_TRUE(bag.ok()) << bag.message();
  testing::ExpectSmallRobot(*bag);
  testing::ExpectSmallRobotTopics(*bag);
}

TEST_P(SqliteFixtureTest, IsReadAsARobotBagFromItsDirectoryOrItsFile) {
  const std::string directory = kBags + GetParam();
  EXPECT_TRUE(LooksLikeRobotBag(directory));
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(directory)) {
    if (entry.path().extension() != ".yaml") files.push_back(entry.path().string());
  }
  ASSERT_EQ(1u, files.size());
  EXPECT_TRUE(LooksLikeRobotBag(files[0]));
  for (const std::string& path : {directory, files[0]}) {
    const auto bag = ReadRobotBag(path);
    ASSERT_TRUE(bag.ok()) << bag.message();
    EXPECT_EQ(files[0], bag->source);
    testing::ExpectSmallRobot(*bag);
  }
}

TEST_P(SqliteFixtureTest, DecodesOnlyTheRequestedTopics) {
  BagReadOptions options;
  options.topics = {"/scan", "/tf_static", "/no_such_topic"};
  const auto bag = ReadSqliteBag(kBags + GetParam(), options);
  ASSERT_TRUE(bag.ok()) << bag.message();
  EXPECT_EQ(20u, bag->scans.at("/scan").size());
  EXPECT_TRUE(bag->joint_states.empty());
  EXPECT_TRUE(bag->odometry.empty());
  EXPECT_TRUE(bag->tf.empty());
  EXPECT_EQ(1u, bag->tf_static.size());
  testing::ExpectSmallRobotTopics(*bag);  // Counted all the same.
}

INSTANTIATE_TEST_SUITE_P(Fixtures, SqliteFixtureTest, ::testing::ValuesIn(kFixtures),
                         [](const auto& info) { return info.param.substr(12); });

// The same messages from the MCAP and the sqlite3 storage, bit for bit.
TEST(SqliteBagReaderTest, AgreesWithTheMcapBitForBit) {
  const auto mcap = ReadMcapBag(kBags + "small_robot_zstd.mcap");
  const auto db3 = ReadSqliteBag(kBags + "small_robot_db3_humble_message");
  ASSERT_TRUE(mcap.ok()) << mcap.message();
  ASSERT_TRUE(db3.ok()) << db3.message();
  const auto& a = mcap->scans.at("/scan");
  const auto& b = db3->scans.at("/scan");
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].record, b[i].record);
    EXPECT_EQ(a[i].log_time_s, b[i].log_time_s);
    ASSERT_EQ(a[i].ranges_m.size(), b[i].ranges_m.size());
    EXPECT_EQ(0, std::memcmp(a[i].ranges_m.data(), b[i].ranges_m.data(),
                             a[i].ranges_m.size() * sizeof(float)));
  }
}

// A split bag (two files) reads as one recording: every message once, in log-time order.
TEST(SqliteBagReaderTest, ReadsASplitBagAsOne) {
  const auto split = ReadSqliteBag(kBags + "sim_robot_db3");
  const auto whole = ReadMcapBag(kBags + "sim_robot_zstd.mcap");
  ASSERT_TRUE(split.ok()) << split.message();
  ASSERT_TRUE(whole.ok()) << whole.message();
  ASSERT_EQ(whole->topics.size(), split->topics.size());
  for (size_t i = 0; i < whole->topics.size(); ++i) {
    EXPECT_EQ(whole->topics[i].message_count, split->topics[i].message_count);
  }
  ASSERT_EQ(whole->scans.at("/scan").size(), split->scans.at("/scan").size());
  ASSERT_EQ(whole->joint_states.size(), split->joint_states.size());
  for (const auto& [topic, joints] : whole->joint_states) {
    const auto& other = split->joint_states.at(topic);
    ASSERT_EQ(joints.size(), other.size());
    for (size_t k = 0; k < joints.size(); ++k) {
      EXPECT_EQ(joints[k].log_time_s, other[k].log_time_s);
      EXPECT_EQ(joints[k].position, other[k].position);
    }
  }
}

class SqliteBagErrorTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::MakeScratchDir("sqlite_bag_reader_test_"); }
  void TearDown() override { fs::remove_all(dir_); }

  // A copy of the uncompressed small robot's database, changed by `sql`.
  std::string Altered(const std::string& name, const std::string& sql) {
    const std::string path = (dir_ / name).string();
    fs::copy_file(kBags + "small_robot_db3/small_robot_db3_0.db3", path);
    sqlite3* db = nullptr;
    EXPECT_EQ(SQLITE_OK, sqlite3_open(path.c_str(), &db));
    char* error = nullptr;
    EXPECT_EQ(SQLITE_OK, sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error))
        << (error ? error : "");
    sqlite3_free(error);
    sqlite3_close(db);
    return path;
  }

  void ExpectError(const std::string& path, const std::vector<std::string>& needles) {
    const auto bag = ReadRobotBag(path);
    ASSERT_FALSE(bag.ok()) << path;
    for (const std::string& needle : needles) {
      EXPECT_NE(bag.message().find(needle), std::string::npos)
          << "'" << needle << "' not in: " << bag.message();
    }
  }

  fs::path dir_;
};

TEST_F(SqliteBagErrorTest, TruncatedDatabaseIsNamed) {
  std::string bytes;
  ASSERT_TRUE(ReadWholeFile(kBags + "small_robot_db3/small_robot_db3_0.db3", &bytes).ok());
  for (const size_t keep : {bytes.size() / 2, bytes.size() - 4096, size_t{100}}) {
    const std::string path = (dir_ / "cut.db3").string();
    ASSERT_TRUE(WriteWholeFile(path, bytes.substr(0, keep)).ok());
    ExpectError(path, {path, "SQLite says", "truncated or corrupt"});
  }
}

TEST_F(SqliteBagErrorTest, ADb3FileThatIsNoDatabaseIsNamed) {
  const std::string path = (dir_ / "notes.db3").string();
  ASSERT_TRUE(WriteWholeFile(path, "these are my notes, not a bag\n").ok());
  ExpectError(path, {path, "not a database"});
}

TEST_F(SqliteBagErrorTest, ADatabaseWithoutMessagesIsNotABag) {
  ExpectError(Altered("no_messages.db3", "DROP TABLE messages"),
              {"no_messages.db3: not a rosbag2 database", "no 'messages' table", "topics"});
}

TEST_F(SqliteBagErrorTest, MessagesOnAnUndefinedTopicAreNamed) {
  ExpectError(Altered("orphans.db3", "DELETE FROM topics WHERE name = '/odom'"),
              {"orphans.db3", "40 messages are on topic id", "topics table does not define"});
}

TEST_F(SqliteBagErrorTest, AGarbledMessageNamesItsTopicAndId) {
  ExpectError(Altered("garbled.db3",
                      "UPDATE messages SET data = x'00010000ffffff7f' WHERE id = (SELECT MIN(id) "
                      "FROM messages WHERE topic_id = (SELECT id FROM topics WHERE name = "
                      "'/joint_states'))"),
              {"garbled.db3: topic '/joint_states' message id "});
}

TEST_F(SqliteBagErrorTest, ATruncatedCompressedMessageIsNamed) {
  // A zstd frame header (magic, a frame stating 200 bytes) and nothing more.
  ExpectError(Altered("cut_frame.db3",
                      "UPDATE messages SET data = x'28b52ffd2064c8' WHERE id = (SELECT MIN(id) "
                      "FROM messages WHERE topic_id = (SELECT id FROM topics WHERE name = "
                      "'/scan'))"),
              {"cut_frame.db3: topic '/scan' message id ", "zstd"});
}

TEST_F(SqliteBagErrorTest, ATruncatedCompressedFileIsNamed) {
  const fs::path source = kBags + "small_robot_db3_foxy_file/small_robot_db3_foxy_file_0.db3.zstd";
  std::string bytes;
  ASSERT_TRUE(ReadWholeFile(source.string(), &bytes).ok());
  const std::string path = (dir_ / "cut.db3.zstd").string();
  ASSERT_TRUE(WriteWholeFile(path, bytes.substr(0, bytes.size() / 2)).ok());
  ExpectError(path, {path, "zstd data truncated"});
}

TEST_F(SqliteBagErrorTest, AnUnknownCompressionIsNamed) {
  const fs::path bag = dir_ / "lz4_bag";
  fs::create_directories(bag);
  fs::copy_file(kBags + "small_robot_db3/small_robot_db3_0.db3", bag / "lz4_bag_0.db3");
  std::ofstream(bag / "metadata.yaml") << "rosbag2_bagfile_information:\n  version: 5\n"
                                       << "  storage_identifier: sqlite3\n"
                                       << "  compression_format: lz4\n"
                                       << "  compression_mode: FILE\n";
  ExpectError(bag.string(), {"metadata.yaml: compression_format 'lz4'", "zstd"});
}

TEST_F(SqliteBagErrorTest, ADirectoryWithoutDatabasesIsNamed) {
  const fs::path bag = dir_ / "empty_bag";
  fs::create_directories(bag);
  ExpectError((bag / "run_0.db3").string(), {"no such file"});
  const auto read = ReadSqliteBag(bag.string());
  ASSERT_FALSE(read.ok());
  EXPECT_NE(read.message().find("holds no .db3 or .db3.zstd file"), std::string::npos)
      << read.message();
}

}  // namespace
}  // namespace calib
