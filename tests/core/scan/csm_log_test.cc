#include <calib/core/scan/csm_log.h>
#include <calib/core/text_file.h>
#include <calib/core/text_number.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "tests/bz2_compress.h"
#include "tests/scratch_dir.h"

namespace calib {
namespace {

// Two beams at −0.1 and 0.1 rad, the second without a return.
std::string Record(double t_s, int left, int right, double left_t_s, double right_t_s) {
  const auto stamp = [](double t) {
    const double s = std::floor(t);
    return "[" + std::to_string(static_cast<int64_t>(s)) + ", " +
           std::to_string(static_cast<int64_t>(std::round(1e6 * (t - s)))) + "]";
  };
  return "{\"nrays\": 2, \"min_theta\": -0.1, \"max_theta\": 0.1, \"theta\": [-0.1, 0.1], "
         "\"readings\": [1.5, null], \"valid\": [1, 0], \"odometry\": [0, 0, 0], "
         "\"timestamp\": " +
         stamp(t_s) + ", \"left\": " + std::to_string(left) +
         ", \"right\": " + std::to_string(right) + ", \"leftTimestamp\": " + stamp(left_t_s) +
         ", \"rightTimestamp\": " + stamp(right_t_s) + "}\n";
}

TEST(CsmLog, ScansAndEncoderCountsAsABagHoldsThem) {
  // The right encoder is read 2 ms after the left, both moving at 1000 counts/s; the third scan
  // carries the second's reading again.
  const std::string text = Record(10.0, 0, 0, 9.998, 10.0) + Record(10.2, 200, -200, 10.198, 10.2) +
                           Record(10.4, 200, -200, 10.198, 10.2) +
                           Record(10.6, 600, -600, 10.598, 10.6);
  const StatusOr<RobotMessages> bag = ReadCsmLogText(text, "log.log");
  ASSERT_TRUE(bag.ok()) << bag.message();
  const std::vector<LaserScan>& scans = bag->scans.at("scans");
  ASSERT_EQ(scans.size(), 4u);
  EXPECT_DOUBLE_EQ(scans[1].stamp_s, 10.2);
  EXPECT_DOUBLE_EQ(scans[0].angle_min_rad, -0.1);
  EXPECT_DOUBLE_EQ(scans[0].angle_increment_rad, 0.2);
  EXPECT_TRUE(scans[0].IsReturn(0));
  EXPECT_FALSE(scans[0].IsReturn(1));
  EXPECT_EQ(scans[2].record, 2);

  const std::vector<JointState>& joints = bag->joint_states.at("encoders");
  ASSERT_EQ(joints.size(), 3u);  // The repeated reading is one sample.
  for (const JointState& j : joints) {
    // At the midpoint of the two stamps, each wheel interpolated along its own readings
    // (extrapolated before the first right reading and after the last left one).
    EXPECT_NEAR(j.position[0], 1000.0 * (j.stamp_s - 9.998), 1e-6) << j.stamp_s;
    EXPECT_NEAR(j.position[1], -1000.0 * (j.stamp_s - 10.0), 1e-6) << j.stamp_s;
  }
  EXPECT_NEAR(joints[1].stamp_s, 10.199, 1e-9);
  EXPECT_DOUBLE_EQ(bag->joint_counts_per_turn.at("encoders"), kCensiKheperaCountsPerTurn);
  EXPECT_TRUE(bag->odometry.empty());  // Zero everywhere: the robot did not report any.
}

TEST(CsmLog, NonFiniteLiteralsAndStreamsOfObjectsAreRead) {
  // Python's json writes NaN; records may share a line.
  std::string text =
      "{\"readings\": [NaN, 2.0, Infinity, 0.004], \"min_theta\": -1, \"max_theta\": 2, "
      "\"timestamp\": [5, 0], \"odometry\": [0.1, 0, 0]}{\"readings\": [1, 2, 3], "
      "\"min_theta\": -1, \"max_theta\": 1, \"timestamp\": [5, 200000], \"odometry\": [0.2, 0, "
      "0.1]}";
  const StatusOr<RobotMessages> bag = ReadCsmLogText(text, "py.log");
  ASSERT_TRUE(bag.ok()) << bag.message();
  const LaserScan& scan = bag->scans.at("scans").front();
  EXPECT_FALSE(scan.IsReturn(0));
  EXPECT_TRUE(scan.IsReturn(1));
  EXPECT_FALSE(scan.IsReturn(2));
  EXPECT_FALSE(scan.IsReturn(3));  // A Hokuyo's error code 4.
  EXPECT_DOUBLE_EQ(scan.angle_increment_rad, 1.0);
  EXPECT_TRUE(bag->joint_states.empty());
  ASSERT_EQ(bag->odometry.at("odometry").size(), 2u);
  EXPECT_DOUBLE_EQ(bag->odometry.at("odometry")[1].position.x(), 0.2);
}

TEST(CsmLog, BadRecordsAreNamed) {
  const std::string good = Record(1.0, 0, 0, 1.0, 1.0);
  const auto error = [](const std::string& text) {
    const StatusOr<RobotMessages> bag = ReadCsmLogText(text, "bad.log");
    return bag.ok() ? std::string("ok") : bag.message();
  };
  EXPECT_NE(error(good + good.substr(0, 60))
                .find("bad.log record 1 (line 2): the file ends "
                      "inside the record (truncated)"),
            std::string::npos)
      << error(good + good.substr(0, 60));
  EXPECT_NE(error(good + "{\"readings\": [1], \"theta\": [0]}")
                .find("record 1 (line 2): no "
                      "\"timestamp\""),
            std::string::npos);
  EXPECT_NE(error("{\"readings\": [1, 2, 3], \"theta\": [0, 0.1, 0.3], \"timestamp\": [1, 0]}")
                .find("theta[1] = 0.1 is off the scan's even grid"),
            std::string::npos);
  EXPECT_NE(error("{\"readings\": [1], \"theta\": [0], \"timestamp\": [1, 0], \"left\": 3}")
                .find("\"left\" and \"right\" must both be encoder counts"),
            std::string::npos);
  EXPECT_NE(error("{\"readings\": [1, 2], \"nrays\": 3, \"theta\": [0, 1], \"timestamp\": [1, "
                  "0]}")
                .find("nrays is not the number of readings (2)"),
            std::string::npos);
  EXPECT_NE(error("[1, 2]").find("record 0 (line 1): expected a JSON object"), std::string::npos);
  // Units mixed up: angles in degrees, ranges in millimetres.
  EXPECT_NE(error("{\"readings\": [1, 2], \"min_theta\": -120, \"max_theta\": 120, "
                  "\"timestamp\": [1, 0]}")
                .find("the beams span 240 rad, more than a circle: are the angles in degrees?"),
            std::string::npos);
  EXPECT_NE(error("{\"readings\": [1500, 2400, 3100], \"min_theta\": -1, \"max_theta\": 1, "
                  "\"timestamp\": [1, 0]}")
                .find("bad.log: the first scans' median reading is 2400: are the readings in "
                      "millimetres?"),
            std::string::npos);
  EXPECT_NE(error("{\"T\": 1, \"phi_l\": 1}")
                .find("no \"readings\" (the ranges of a scan): is "
                      "it a CSM laser log?"),
            std::string::npos);
  EXPECT_NE(error(good + "{\"readings\": [], \"timestamp\": [2, 0]}")
                .find("record 1 (line 2): \"readings\" must be a non-empty array"),
            std::string::npos);
  EXPECT_NE(error("  \n").find("bad.log: no scan records (empty log)"), std::string::npos);
}

// What a test compares of two reads of one log.
std::string Summary(const StatusOr<RobotMessages>& bag) {
  if (!bag.ok()) return bag.message();
  std::string out;
  for (const LaserScan& scan : bag->scans.at("scans")) {
    out += Num(scan.stamp_s) + " " + Num(scan.angle_min_rad) + " " + Num(scan.angle_increment_rad);
    for (float r : scan.ranges_m) out += " " + Num(r);
    out += "\n";
  }
  for (const JointState& j : bag->joint_states.at("encoders")) {
    out += Num(j.stamp_s) + " " + Num(j.position[0]) + " " + Num(j.position[1]) + "\n";
  }
  return out;
}

// A log read in pieces, cut anywhere (inside a number, a string, between records), reads as the
// whole text does, and so do its errors.
TEST(CsmLog, PiecesCutAnywhereReadAsTheWhole) {
  std::string text;
  for (int k = 0; k < 12; ++k) {
    text += Record(1.0 + 0.2 * k, 7 * k, -5 * k, 0.999 + 0.2 * k, 1.0 + 0.2 * k);
    if (k % 3 == 0) text += "\n\n";
  }
  const auto pieces = [](const std::string& all, size_t size) {
    CsmLogReader reader("cut.log");
    for (size_t p = 0; p < all.size(); p += size) {
      const Status fed = reader.Feed(std::string_view(all).substr(p, size));
      if (!fed.ok()) return StatusOr<RobotMessages>(fed);
    }
    return reader.Finish();
  };
  const std::string whole = Summary(ReadCsmLogText(text, "cut.log"));
  ASSERT_EQ(std::count(whole.begin(), whole.end(), '\n'), 12 + 12) << whole;
  for (size_t size : {1, 2, 3, 7, 64, 500, 100000}) {
    EXPECT_EQ(Summary(pieces(text, size)), whole) << size;
  }
  const std::string cut = text.substr(0, text.size() - 30);
  const std::string error = Summary(ReadCsmLogText(cut, "cut.log"));
  EXPECT_NE(error.find("cut.log record 11 (line 20): the file ends inside the record"),
            std::string::npos)
      << error;
  for (size_t size : {1, 5, 64}) EXPECT_EQ(Summary(pieces(cut, size)), error) << size;
  // After an error the reader stays at it.
  CsmLogReader reader("bad.log");
  EXPECT_FALSE(reader.Feed("[1]").ok());
  EXPECT_FALSE(reader.Feed(text).ok());
  EXPECT_NE(reader.Finish().message().find("expected a JSON object"), std::string::npos);
}

// Fields the reader does not use may hold anything JSON allows (nested objects, escaped strings)
// and are skipped; a reading that is no number (a nested array, a string) is no return.
TEST(CsmLog, AnyJsonInOtherFieldsIsSkipped) {
  const std::string text =
      "{\"extra\": {\"a\": [1, {\"b\": \"x\\\"}\"}], \"c\": true}, \"note\": \"tab\\t\", "
      "\"readings\": [1.5, [2], \"3\", 0, -Infinity, 2.5], \"min_theta\": -1, "
      "\"max_theta\": 1, \"timestamp\": [3, 5e5], \"flag\": false, \"sensor\": null}\n"
      "{ \"readings\" : [ 1.0 , 2.0 ] , \"theta\" : [ -0.5 , 0.5 ] , \"timestamp\" : 4.25 }";
  const StatusOr<RobotMessages> bag = ReadCsmLogText(text, "any.log");
  ASSERT_TRUE(bag.ok()) << bag.message();
  const std::vector<LaserScan>& scans = bag->scans.at("scans");
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_DOUBLE_EQ(scans[0].stamp_s, 3.5);
  EXPECT_TRUE(scans[0].IsReturn(0));
  EXPECT_FALSE(scans[0].IsReturn(1));
  EXPECT_FALSE(scans[0].IsReturn(2));
  EXPECT_FALSE(scans[0].IsReturn(4));
  EXPECT_FLOAT_EQ(scans[0].ranges_m[5], 2.5f);
  EXPECT_DOUBLE_EQ(scans[1].stamp_s, 4.25);
  EXPECT_DOUBLE_EQ(scans[1].angle_increment_rad, 1.0);
  // Not JSON at all, however it is cut.
  const StatusOr<RobotMessages> bad =
      ReadCsmLogText("{\"readings\": [1, 2], \"timestamp\": [1, 0] \"x\": 1}", "bad.log");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.message().find("bad.log record 0 (line 1): not a JSON object"), std::string::npos)
      << bad.message();
}

std::string Bz2(const std::string& text) { return testing::Bz2Compress(text); }

// The authors' archives hold log.log.bz2: read as it is, told from a tuple file by its content;
// a file that pbzip2 wrote as several streams reads whole; a truncated one is an error.
TEST(CsmLog, Bz2FilesAreReadAndToldApart) {
  const testing::ScratchDir dir("csm_log_test");
  const auto file = [&](const char* name) { return (dir.path() / name).string(); };
  std::string text;
  for (int k = 0; k < 50; ++k)
    text += Record(1.0 + 0.2 * k, 10 * k, 10 * k, 1.0 + 0.2 * k, 1.0 + 0.2 * k);
  const std::string path = file("log.log.bz2");
  ASSERT_TRUE(
      WriteWholeFile(path, Bz2(text.substr(0, text.size() / 2)) + Bz2(text.substr(text.size() / 2)))
          .ok());
  EXPECT_TRUE(LooksLikeCsmLog(path));
  const StatusOr<RobotMessages> bag = ReadCsmLog(path);
  ASSERT_TRUE(bag.ok()) << bag.message();
  EXPECT_EQ(bag->scans.at("scans").size(), 50u);
  EXPECT_EQ(bag->source, path);

  const std::string plain = file("log.log");
  ASSERT_TRUE(WriteWholeFile(plain, text).ok());
  EXPECT_TRUE(LooksLikeCsmLog(plain));
  const std::string tuples = file("l90.tuple");
  ASSERT_TRUE(
      WriteWholeFile(tuples, "{ \"T\": 1, \"phi_l\": 1, \"phi_r\": 1, \"sm\": [0, 0, 0] }").ok());
  EXPECT_FALSE(LooksLikeCsmLog(tuples));
  EXPECT_FALSE(LooksLikeCsmLog(dir.path().string()));

  EXPECT_TRUE(IsBz2File(path));
  EXPECT_FALSE(IsBz2File(plain));

  const std::string cut = file("cut.log.bz2");
  const std::string packed = Bz2(text);
  ASSERT_TRUE(WriteWholeFile(cut, packed.substr(0, packed.size() - 40)).ok());
  const StatusOr<RobotMessages> truncated = ReadCsmLog(cut);
  ASSERT_FALSE(truncated.ok());
  EXPECT_NE(truncated.message().find("cut.log.bz2: bz2 data end before their stream does"),
            std::string::npos)
      << truncated.message();
}

// An archive of experiments (exp1/log.log.bz2, exp2/log.log): one recording, the second log's
// restarted clock and counters moved to go on after the first's, its start a restart.
TEST(CsmLog, ExperimentsOfOneRobotAreJoined) {
  const testing::ScratchDir dir("csm_log_test");
  std::filesystem::create_directories(dir.path() / "exp1");
  std::filesystem::create_directories(dir.path() / "exp2");
  std::string first, second;
  for (int k = 0; k < 5; ++k) {
    const double t = 100.0 + 0.2 * k;
    first += Record(t, 10 * k, 20 * k, t, t);
    second += Record(t - 0.4, 5 * k, 5 * k, t - 0.4, t - 0.4);  // A clock that overlaps.
  }
  ASSERT_TRUE(WriteWholeFile((dir.path() / "exp1" / "log.log.bz2").string(), Bz2(first)).ok());
  ASSERT_TRUE(WriteWholeFile((dir.path() / "exp2" / "log.log").string(), second).ok());
  ASSERT_TRUE(WriteWholeFile((dir.path() / "exp2" / "notes.txt").string(), "not a log").ok());
  EXPECT_TRUE(IsCsmLogDirectory(dir.path().string()));
  const std::vector<std::string> logs = CsmLogsIn(dir.path().string());
  ASSERT_EQ(logs.size(), 2u);
  const StatusOr<RobotMessages> bag = ReadCsmLogs(logs, "l90");
  ASSERT_TRUE(bag.ok()) << bag.message();
  EXPECT_EQ(bag->source, "l90");
  // exp2 starts first, and exp1, which starts before exp2 ends, follows 10 s after its end.
  const std::vector<LaserScan>& scans = bag->scans.at("scans");
  ASSERT_EQ(scans.size(), 10u);
  EXPECT_NEAR(scans[4].stamp_s, 100.4, 1e-9);
  EXPECT_NEAR(scans[5].stamp_s, 110.4, 1e-9);
  ASSERT_EQ(bag->restarts_s.size(), 1u);
  EXPECT_NEAR(bag->restarts_s[0], 110.4, 1e-9);
  EXPECT_EQ(scans[5].record, 5);
  const std::vector<JointState>& joints = bag->joint_states.at("encoders");
  ASSERT_EQ(joints.size(), 10u);
  EXPECT_DOUBLE_EQ(joints[5].position[0], 20.0);  // exp2 ended at 20 counts; exp1 goes on.
  EXPECT_DOUBLE_EQ(joints[6].position[1], 40.0);
  EXPECT_EQ(bag->topics.front().message_count, 10);
}

}  // namespace
}  // namespace calib
