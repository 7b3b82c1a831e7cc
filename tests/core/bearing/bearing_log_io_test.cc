#include <calib/core/bearing/bearing_log_io.h>
#include <calib/core/bearing/bearing_simulator.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/scratch_dir.h"

namespace calib {
namespace {

namespace fs = std::filesystem;

class BearingLogIoTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::MakeScratchDir("bearing_io_"); }
  void TearDown() override { fs::remove_all(dir_); }

  void Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
  }
  // A small valid log, with one file replaced.
  void WriteLog(const std::string& odometry, const std::string& bearings, const std::string& meta) {
    Write("odometry.csv", odometry);
    Write("bearings.csv", bearings);
    Write("meta.json", meta);
  }
  std::string Read() {
    const StatusOr<BearingLog> log = ReadBearingLog(dir_.string());
    return log.ok() ? "" : log.message();
  }

  fs::path dir_;
};

const char kOdometry[] = "run,t,left,right\n1,0,0,0\n1,1,0.1,0.2\n1,2,0.2,0.4\n2,5,0,0\n2,6,1,1\n";
const char kBearings[] = "run,t,bearing\n1,0.5,0.1\n1,1.5,-0.2\n2,5.5,3.0\n";
const char kMeta[] = "{\"wheel_radius\": 0.3, \"wheelbase\": 0.5}\n";

TEST_F(BearingLogIoTest, RoundTripIsExact) {
  BearingSimOptions o;
  o.bearing_noise_rad = 0.01;
  o.initial_distance_run = 3;
  const BearingLog log = SimulateBearingLog(o);
  ASSERT_TRUE(WriteBearingLog(log, dir_.string()).ok());
  const StatusOr<BearingLog> back = ReadBearingLog(dir_.string());
  ASSERT_TRUE(back.ok()) << back.message();
  EXPECT_EQ(back->meta.wheel_radius_m, log.meta.wheel_radius_m);
  EXPECT_EQ(back->meta.wheelbase_m, log.meta.wheelbase_m);
  ASSERT_TRUE(back->meta.initial_distance.has_value());
  EXPECT_EQ(back->meta.initial_distance->run, 3);
  EXPECT_EQ(back->meta.initial_distance->meters, log.meta.initial_distance->meters);
  ASSERT_EQ(back->runs.size(), log.runs.size());
  for (size_t i = 0; i < log.runs.size(); ++i) {
    ASSERT_EQ(back->runs[i].odometry.size(), log.runs[i].odometry.size());
    ASSERT_EQ(back->runs[i].bearings.size(), log.runs[i].bearings.size());
    for (size_t j = 0; j < log.runs[i].odometry.size(); ++j) {
      EXPECT_EQ(back->runs[i].odometry[j].t_s, log.runs[i].odometry[j].t_s);
      EXPECT_EQ(back->runs[i].odometry[j].left_rad, log.runs[i].odometry[j].left_rad);
      EXPECT_EQ(back->runs[i].odometry[j].right_rad, log.runs[i].odometry[j].right_rad);
    }
    for (size_t j = 0; j < log.runs[i].bearings.size(); ++j) {
      EXPECT_EQ(back->runs[i].bearings[j].t_s, log.runs[i].bearings[j].t_s);
      EXPECT_EQ(back->runs[i].bearings[j].bearing_rad, log.runs[i].bearings[j].bearing_rad);
    }
  }
  EXPECT_TRUE(ValidateBearingLog(*back).ok());
}

TEST_F(BearingLogIoTest, AcceptsReorderedColumnsCrlfBomCommentsAndExtraColumns) {
  WriteLog("\xEF\xBB\xBF# encoders\r\nRight, t ,run,left,extra\r\n0,0,1,0,x\r\n0.2,1,1,0.1,y\r\n",
           "bearing,run,t\n\n0.1,1,0.5\n", kMeta);
  const StatusOr<BearingLog> log = ReadBearingLog(dir_.string());
  ASSERT_TRUE(log.ok()) << log.message();
  ASSERT_EQ(log->runs.size(), 1u);
  EXPECT_EQ(log->runs[0].odometry[1].right_rad, 0.2);
  EXPECT_EQ(log->runs[0].odometry[1].left_rad, 0.1);
  EXPECT_EQ(log->runs[0].odometry[1].line, 4);
  EXPECT_EQ(log->runs[0].bearings[0].bearing_rad, 0.1);
  EXPECT_EQ(log->runs[0].bearings[0].line, 3);
}

TEST_F(BearingLogIoTest, ValidLogReads) {
  WriteLog(kOdometry, kBearings,
           "{\"wheel_radius\": 0.3, \"wheelbase\": 0.5, "
           "\"initial_distance\": {\"run\": 2, \"meters\": 1.5}}");
  const StatusOr<BearingLog> log = ReadBearingLog(dir_.string());
  ASSERT_TRUE(log.ok()) << log.message();
  ASSERT_EQ(log->runs.size(), 2u);
  EXPECT_EQ(log->runs[1].id, 2);
  EXPECT_EQ(log->meta.initial_distance->meters, 1.5);
}

// Exact duplicate records are dropped and counted in the pooled timing of each stream.
TEST_F(BearingLogIoTest, ExactDuplicatesAreDroppedAndTimingIsPooled) {
  WriteLog("run,t,left,right\n1,0,0,0\n1,1,0.1,0.2\n1,1,0.1,0.2\n1,2,0.2,0.4\n2,5,0,0\n2,6,1,1\n",
           "run,t,bearing\n1,0.5,0.1\n1,0.5,0.1\n1,1.5,-0.2\n2,5.5,3.0\n", kMeta);
  const StatusOr<BearingLog> log = ReadBearingLog(dir_.string());
  ASSERT_TRUE(log.ok()) << log.message();
  ASSERT_EQ(log->runs[0].odometry.size(), 3u);
  EXPECT_EQ(log->runs[0].odometry[2].line, 5);
  ASSERT_EQ(log->runs[0].bearings.size(), 2u);
  EXPECT_EQ(log->runs[0].bearings[1].line, 4);
  ASSERT_EQ(log->stream_timing.size(), 2u);
  const StreamTiming& odometry = log->stream_timing[0];
  EXPECT_EQ(odometry.stream, "odometry");
  EXPECT_EQ(odometry.source, (dir_ / "odometry.csv").string());
  EXPECT_EQ(odometry.records, 6);
  EXPECT_EQ(odometry.samples, 5);
  EXPECT_EQ(odometry.duplicates_dropped, 1);
  EXPECT_NEAR(odometry.period_s, 1.0, 1e-12);
  const StreamTiming& bearings = log->stream_timing[1];
  EXPECT_EQ(bearings.stream, "bearings");
  EXPECT_EQ(bearings.records, 4);
  EXPECT_EQ(bearings.duplicates_dropped, 1);
  bool pooled = false;
  for (const std::string& note : bearings.notes)
    pooled |= note.find("pooled over 2 run") != std::string::npos;
  EXPECT_TRUE(pooled);
  // Each file's duplicates are said once, in a warning.
  const std::vector<std::string> expected = {
      (dir_ / "odometry.csv").string() + ": 1 exact duplicate record(s) dropped",
      (dir_ / "bearings.csv").string() + ": 1 exact duplicate record(s) dropped"};
  for (const std::string& sentence : expected) {
    bool said = false;
    for (const std::string& w : log->warnings) said |= w.find(sentence) == 0;
    EXPECT_TRUE(said) << sentence;
  }
}

// Every error names the file, the line where there is one, and the problem.
struct BadCase {
  const char* what;
  std::string odometry, bearings, meta;
  std::vector<std::string> expect;  // Substrings of the message.
};

TEST_F(BearingLogIoTest, EveryReaderErrorIsExplained) {
  const std::string o = kOdometry, b = kBearings, m = kMeta;
  const std::vector<BadCase> cases = {
      {"empty odometry", "", b, m, {"odometry.csv", "empty file", "run,t,left,right"}},
      {"no samples", "run,t,left,right\n", b, m, {"odometry.csv", "no samples"}},
      {"missing column", "run,t,left\n1,0,0\n", b, m, {"odometry.csv:1", "no column 'right'"}},
      {"duplicate column", "run,t,left,right,t\n1,0,0,0,0\n", b, m, {"odometry.csv:1", "twice"}},
      {"field count",
       "run,t,left,right\n1,0,0,0\n1,1,0\n",
       b,
       m,
       {"odometry.csv:3", "expected 4", "found 3"}},
      {"not a number",
       "run,t,left,right\n1,0,0,0\n1,abc,0,0\n",
       b,
       m,
       {"odometry.csv:3", "'t'", "not a number", "abc"}},
      {"nan",
       "run,t,left,right\n1,0,0,0\n1,1,nan,0\n",
       b,
       m,
       {"odometry.csv:3", "'left'", "finite"}},
      {"inf",
       "run,t,left,right\n1,0,0,0\n1,1,0,inf\n",
       b,
       m,
       {"odometry.csv:3", "'right'", "finite"}},
      {"empty field",
       "run,t,left,right\n1,0,0,0\n1,,0,0\n",
       b,
       m,
       {"odometry.csv:3", "'t' is empty"}},
      {"run id", "run,t,left,right\n1.5,0,0,0\n", b, m, {"odometry.csv:2", "integer run id"}},
      {"time order",
       "run,t,left,right\n1,0,0,0\n1,2,0,0\n1,1.5,0,0\n",
       b,
       m,
       {"odometry.csv:4", "run 1", "not after", "line 3"}},
      {"repeated time, other values",
       "run,t,left,right\n1,0,0,0\n1,2,0,0\n1,2,0.1,0\n",
       b,
       m,
       {"odometry.csv: line 3 and line 4 share t=2 but differ in left"}},
      {"one sample",
       "run,t,left,right\n1,0,0,0\n1,1,0,0\n2,0,0,0\n",
       "run,t,bearing\n1,0.5,0\n",
       m,
       {"odometry.csv:4", "run 2", "at least two"}},
      {"bearing run unknown",
       o,
       "run,t,bearing\n1,0.5,0\n7,0.5,0\n",
       m,
       {"bearings.csv:3", "run 7", "no encoder samples"}},
      {"bearing outside span",
       o,
       "run,t,bearing\n1,0.5,0\n1,2.5,0\n2,5.5,0\n",
       m,
       {"bearings.csv:3", "run 1", "outside", "[0, 2]", "lines 2–4"}},
      {"bearing before span", o, "run,t,bearing\n1,-0.5,0\n", m, {"bearings.csv:2", "outside"}},
      {"bearing in degrees",
       o,
       "run,t,bearing\n1,0.5,45\n",
       m,
       {"bearings.csv:2", "outside (−π, π]", "radians"}},
      {"bearing nan",
       o,
       "run,t,bearing\n1,0.5,NaN\n",
       m,
       {"bearings.csv:2", "'bearing'", "finite"}},
      {"bearing order",
       o,
       "run,t,bearing\n1,0.5,0\n1,0.4,0\n2,5.5,0\n",
       m,
       {"bearings.csv:3", "not after"}},
      {"repeated bearing time, other value",
       o,
       "run,t,bearing\n1,0.5,0\n1,0.5,0.1\n2,5.5,0\n",
       m,
       {"bearings.csv: line 2 and line 3 share t=0.5 but differ in bearing"}},
      {"run without bearings",
       o,
       "run,t,bearing\n1,0.5,0\n",
       m,
       {"bearings.csv", "run 2 has no bearings", "lines 5–6"}},
      {"bearings missing column",
       o,
       "run,t,angle\n1,0.5,0\n",
       m,
       {"bearings.csv:1", "no column 'bearing'"}},
      {"no bearings at all", o, "run,t,bearing\n", m, {"bearings.csv", "no samples"}},
      {"bad json",
       o,
       b,
       "{\"wheel_radius\": 0.3,\n \"wheelbase\": }",
       {"meta.json", "JSON", "line 2"}},
      {"not object", o, b, "[1, 2]", {"meta.json", "object", "array"}},
      {"missing radius", o, b, "{\"wheelbase\": 0.5}", {"meta.json", "missing", "wheel_radius"}},
      {"missing wheelbase", o, b, "{\"wheel_radius\": 0.3}", {"meta.json", "missing", "wheelbase"}},
      {"radius string",
       o,
       b,
       "{\"wheel_radius\": \"0.3\",\n\"wheelbase\": 0.5}",
       {"meta.json:1", "wheel_radius", "number", "string"}},
      {"negative wheelbase",
       o,
       b,
       "{\"wheel_radius\": 0.3,\n\"wheelbase\": -0.5}",
       {"meta.json:2", "wheelbase", "positive"}},
      {"distance not object",
       o,
       b,
       "{\"wheel_radius\": 0.3, \"wheelbase\": 0.5, \"initial_distance\": 3}",
       {"meta.json:1", "initial_distance", "object"}},
      {"distance no run",
       o,
       b,
       "{\"wheel_radius\": 0.3, \"wheelbase\": 0.5, \"initial_distance\": {\"meters\": 1}}",
       {"meta.json", "initial_distance.run"}},
      {"distance run not integer",
       o,
       b,
       "{\"wheel_radius\": 0.3, \"wheelbase\": 0.5, \"initial_distance\": {\"run\": 1.5, "
       "\"meters\": 1}}",
       {"meta.json", "initial_distance.run", "integer"}},
      {"distance run unknown",
       o,
       b,
       "{\"wheel_radius\": 0.3, \"wheelbase\": 0.5, \"initial_distance\": {\"run\": 9, "
       "\"meters\": 1}}",
       {"meta.json", "initial_distance.run = 9", "no run"}},
      {"distance no meters",
       o,
       b,
       "{\"wheel_radius\": 0.3, \"wheelbase\": 0.5, \"initial_distance\": {\"run\": 1}}",
       {"meta.json", "initial_distance.meters"}},
      {"distance zero",
       o,
       b,
       "{\"wheel_radius\": 0.3, \"wheelbase\": 0.5, \"initial_distance\": {\"run\": 1, "
       "\"meters\": 0}}",
       {"meta.json", "initial_distance.meters", "positive"}},
  };
  for (const BadCase& c : cases) {
    WriteLog(c.odometry, c.bearings, c.meta);
    const std::string message = Read();
    ASSERT_FALSE(message.empty()) << c.what << ": accepted";
    for (const std::string& part : c.expect) {
      EXPECT_NE(message.find(part), std::string::npos)
          << c.what << ": '" << message << "' lacks '" << part << "'";
    }
  }
}

TEST_F(BearingLogIoTest, MissingFilesAndDirectory) {
  EXPECT_NE(Read().find("odometry.csv: no such file"), std::string::npos) << Read();
  Write("odometry.csv", kOdometry);
  EXPECT_NE(Read().find("bearings.csv: no such file"), std::string::npos) << Read();
  Write("bearings.csv", kBearings);
  EXPECT_NE(Read().find("meta.json: no such file"), std::string::npos) << Read();
  const StatusOr<BearingLog> none = ReadBearingLog((dir_ / "absent").string());
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.message().find("not a directory"), std::string::npos);
  EXPECT_EQ(none.code(), StatusCode::kIo);
}

TEST_F(BearingLogIoTest, ValidateChecksInMemoryLogs) {
  BearingSimOptions o;
  BearingLog log = SimulateBearingLog(o);
  ASSERT_TRUE(ValidateBearingLog(log).ok());
  BearingLog bad = log;
  bad.runs[1].bearings.clear();
  EXPECT_NE(ValidateBearingLog(bad).message().find("run 2 has no bearings"), std::string::npos);
  bad = log;
  bad.runs[0].bearings[3].bearing_rad = std::nan("");
  EXPECT_NE(ValidateBearingLog(bad).message().find("not finite"), std::string::npos);
  bad = log;
  bad.runs[2].bearings.back().t_s += 100.0;
  EXPECT_NE(ValidateBearingLog(bad).message().find("outside the run's odometry time span"),
            std::string::npos);
  bad = log;
  bad.runs[2].id = 1;
  EXPECT_NE(ValidateBearingLog(bad).message().find("unique"), std::string::npos);
  bad = log;
  bad.meta.wheelbase_m = 0.0;
  EXPECT_NE(ValidateBearingLog(bad).message().find("wheelbase"), std::string::npos);
  bad = log;
  bad.meta.initial_distance = InitialDistance{4, 1.0};
  EXPECT_NE(ValidateBearingLog(bad).message().find("names no run"), std::string::npos);
  bad = log;
  bad.runs[0].odometry.resize(1);
  EXPECT_NE(ValidateBearingLog(bad).message().find("at least two"), std::string::npos);
  bad.runs.clear();
  EXPECT_NE(ValidateBearingLog(bad).message().find("no runs"), std::string::npos);
}

}  // namespace
}  // namespace calib
