#include <calib/core/laser/laser_log_io.h>
#include <calib/core/timing/stream_samples.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <random>
#include <string>
#include <vector>

namespace calib {
namespace {

namespace fs = std::filesystem;

// A fresh directory per test so that parallel ctest runs do not collide.
class LaserLogIoTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
    std::random_device random;
    dir_ = fs::temp_directory_path() /
           ("calib_laser_log_io_" + std::string(info->name()) + "_" + std::to_string(random()));
    fs::remove_all(dir_);
    ASSERT_TRUE(fs::create_directories(dir_));
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  std::string Write(const std::string& name, const std::string& text) const {
    const std::string path = Path(name);
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }

  fs::path dir_;
};

template <typename T>
void ExpectError(const StatusOr<T>& result, std::initializer_list<std::string> parts) {
  ASSERT_FALSE(result.ok()) << "expected an error containing '" << *parts.begin() << "'";
  for (const std::string& part : parts) {
    EXPECT_NE(result.message().find(part), std::string::npos)
        << "message: " << result.message() << "\nlacks: " << part;
  }
}

void ExpectSameValues(const LaserLog& a, const LaserLog& b, bool compare_steps) {
  ASSERT_EQ(a.intervals.size(), b.intervals.size());
  EXPECT_EQ(a.has_timestamps, b.has_timestamps);
  for (size_t k = 0; k < a.intervals.size(); ++k) {
    SCOPED_TRACE("interval " + std::to_string(k));
    const LaserInterval& x = a.intervals[k];
    const LaserInterval& y = b.intervals[k];
    EXPECT_EQ(x.start_s, y.start_s);
    EXPECT_EQ(x.duration_s, y.duration_s);
    EXPECT_EQ(x.left_speed, y.left_speed);
    EXPECT_EQ(x.right_speed, y.right_speed);
    EXPECT_EQ(x.sensor_motion, y.sensor_motion);
    EXPECT_EQ(x.gap_before, y.gap_before);
    if (!compare_steps) continue;
    ASSERT_EQ(x.steps.size(), y.steps.size());
    for (size_t s = 0; s < x.steps.size(); ++s) {
      EXPECT_EQ(x.steps[s].duration_s, y.steps[s].duration_s);
      EXPECT_EQ(x.steps[s].left_rad, y.steps[s].left_rad);
      EXPECT_EQ(x.steps[s].right_rad, y.steps[s].right_rad);
    }
  }
}

// Random intervals; start_s summed the way the reader does when there is no t.
LaserLog RandomLog(int n, bool with_gaps, std::mt19937* rng) {
  std::uniform_real_distribution<double> duration(0.05, 1.5);
  std::uniform_real_distribution<double> value(-3.0, 3.0);
  LaserLog log;
  log.has_timestamps = with_gaps;
  double t = with_gaps ? 12.345678901234567 : 0.0;
  for (int k = 0; k < n; ++k) {
    LaserInterval interval;
    if (with_gaps && k % 17 == 5) {
      t += 2.5;
      interval.gap_before = true;
    }
    interval.start_s = t;
    interval.duration_s = duration(*rng);
    interval.left_speed = value(*rng);
    interval.right_speed = value(*rng) * 1e-7;
    interval.sensor_motion = Pose2d(value(*rng) * 1e-3, value(*rng), value(*rng));
    t = interval.start_s + interval.duration_s;
    log.intervals.push_back(interval);
  }
  return log;
}

constexpr char kRecord[] = R"({ "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0.1, 0.2, 0.3] })";

// Two good records on lines 1-2, then `third` on line 3.
std::string ThirdRecord(const std::string& third) {
  return std::string(kRecord) + "\n" + kRecord + "\n" + third;
}

// ---------------------------------------------------------------------------------------------

TEST(LaserFormatTest, ParsesNamesAndRejectsOthers) {
  EXPECT_EQ(*ParseLaserFormat("auto"), LaserFormat::kAuto);
  EXPECT_EQ(*ParseLaserFormat("tuples"), LaserFormat::kTuples);
  EXPECT_EQ(*ParseLaserFormat("json"), LaserFormat::kTuples);
  EXPECT_EQ(*ParseLaserFormat("csv"), LaserFormat::kCsv);
  EXPECT_EQ(*ParseLaserFormat("stream"), LaserFormat::kStream);
  ExpectError(ParseLaserFormat("yaml"), {"yaml", "auto", "tuples", "json", "csv", "stream"});
}

TEST(LaserTuplesTest, ParsesThePublishedLayout) {
  const std::string text =
      "{ \"T\": 7.943960e-01, \"phi_l\": 1.401765e-01, \"phi_r\": -1.373157e-01, \"sm\": [ "
      "1.092608e-03, -5.089714e-04, -2.748851e-02 ] }\n"
      "{ \"T\": 8.048160e-01, \"phi_l\": 4.941486e-01, \"phi_r\": 0.0, \"sm\": [ 2.467056e-05, "
      "8.764928e-04, -1.809825e-01 ] }\n";
  const StatusOr<LaserLog> log = ParseLaserTuples(text, "x.tuple");
  ASSERT_TRUE(log.ok()) << log.message();
  EXPECT_EQ(log->source, "x.tuple");
  EXPECT_FALSE(log->has_timestamps);
  ASSERT_EQ(log->intervals.size(), 2u);
  const LaserInterval& first = log->intervals[0];
  EXPECT_EQ(first.duration_s, 7.943960e-01);
  EXPECT_EQ(first.left_speed, 1.401765e-01);
  EXPECT_EQ(first.right_speed, -1.373157e-01);
  EXPECT_EQ(first.sensor_motion, Pose2d(1.092608e-03, -5.089714e-04, -2.748851e-02));
  EXPECT_EQ(first.start_s, 0.0);
  EXPECT_EQ(first.line, 1);
  EXPECT_EQ(first.record, 1);
  EXPECT_TRUE(first.steps.empty());
  EXPECT_EQ(log->intervals[1].start_s, 7.943960e-01);
  EXPECT_EQ(log->intervals[1].right_speed, 0.0);
  EXPECT_EQ(log->intervals[1].line, 2);
  EXPECT_EQ(log->intervals[1].record, 2);
  EXPECT_FALSE(log->intervals[1].gap_before);
}

TEST(LaserTuplesTest, ReadsAStreamOfValuesNotLines) {
  // `}{`, `} {`, a record split over lines, compact JSON, tabs and \r\n (records that differ: an
  // exact repeat of the record before is a duplicate).
  const std::string other = R"({ "T": 0.5, "phi_l": 1, "phi_r": 2.5, "sm": [0.1, 0.2, 0.3] })";
  const std::string text = std::string(kRecord) + other + " " + kRecord + "\r\n\n" +
                           "{\"T\":0.25,\n\t\"phi_l\" : -1e-3 ,\"phi_r\":3,\r\n \"sm\":[1,\n2,3]}" +
                           "\n" + kRecord;
  const StatusOr<LaserLog> log = ParseLaserTuples(text, "x.tuple");
  ASSERT_TRUE(log.ok()) << log.message();
  ASSERT_EQ(log->intervals.size(), 5u);
  const int lines[] = {1, 1, 1, 3, 7};
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(log->intervals[k].line, lines[k]) << k;
    EXPECT_EQ(log->intervals[k].record, k + 1);
  }
  EXPECT_EQ(log->intervals[3].duration_s, 0.25);
  EXPECT_EQ(log->intervals[3].left_speed, -1e-3);
  EXPECT_EQ(log->intervals[3].sensor_motion, Pose2d(1, 2, 3));
  EXPECT_DOUBLE_EQ(log->intervals[4].start_s, 3 * 0.5 + 0.25);
}

TEST(LaserTuplesTest, OptionalStartTimesMarkGaps) {
  const std::string text =
      R"({"t": 10, "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0, 0, 0]}
         {"t": 10.5000001, "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0, 0, 0]}
         {"T": 0.5, "t": 10.9996, "phi_l": 1, "phi_r": 2, "sm": [0, 0, 0]}
         {"t": 13, "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0, 0, 0]})";
  const StatusOr<LaserLog> log = ParseLaserTuples(text, "x.tuple");
  ASSERT_TRUE(log.ok()) << log.message();
  EXPECT_TRUE(log->has_timestamps);
  ASSERT_EQ(log->intervals.size(), 4u);
  EXPECT_EQ(log->intervals[0].start_s, 10.0);
  EXPECT_EQ(log->intervals[2].start_s, 10.9996);  // Within the 1e-6 + 1e-3·T tolerance.
  EXPECT_EQ(log->intervals[3].start_s, 13.0);
  EXPECT_FALSE(log->intervals[0].gap_before);
  EXPECT_FALSE(log->intervals[1].gap_before);
  EXPECT_FALSE(log->intervals[2].gap_before);
  EXPECT_TRUE(log->intervals[3].gap_before);
}

struct ErrorCase {
  const char* name;
  std::string text;
  std::vector<std::string> parts;
};

TEST(LaserTuplesTest, ErrorsNameFileLineRecordAndProblem) {
  const std::vector<ErrorCase> cases = {
      {"empty", "", {"bad.tuple", "holds no records"}},
      {"white space", " \n\t\r\n ", {"bad.tuple", "holds no records"}},
      {"truncated object",
       ThirdRecord("{ \"T\": 0.5, \"phi_l\": 1,\n \"phi_r\""),
       {"bad.tuple:3:", "record 3", "truncated"}},
      {"truncated after value", ThirdRecord("{ \"T\": 0.5"), {"bad.tuple:3:", "truncated"}},
      {"truncated array",
       ThirdRecord("{ \"T\": 0.5, \"phi_l\": 1, \"phi_r\": 2,\n \"sm\": [0.1, 0.2"),
       {"bad.tuple:3:", "record 3", "truncated", "sm"}},
      {"truncated key", ThirdRecord("{ \"T\": 0.5, \"ph"), {"bad.tuple:3:", "truncated"}},
      {"NaN",
       ThirdRecord(R"({ "T": NaN, "phi_l": 1, "phi_r": 2, "sm": [0.1, 0.2, 0.3] })"),
       {"bad.tuple:3:", "record 3", "T must be finite", "NaN"}},
      {"nan in sm",
       ThirdRecord(R"({ "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0.1, nan, 0.3] })"),
       {"bad.tuple:3:", "record 3", "sm must be finite", "nan"}},
      {"Infinity",
       ThirdRecord(R"({ "T": 0.5, "phi_l": Infinity, "phi_r": 2, "sm": [0.1, 0.2, 0.3] })"),
       {"bad.tuple:3:", "record 3", "phi_l must be finite", "Infinity"}},
      {"-Infinity",
       ThirdRecord(R"({ "T": 0.5, "phi_l": 1, "phi_r": -Infinity, "sm": [0.1, 0.2, 0.3] })"),
       {"bad.tuple:3:", "phi_r must be finite", "-Infinity"}},
      {"overflow",
       ThirdRecord(R"({ "T": 0.5, "phi_l": 1e400, "phi_r": 2, "sm": [0.1, 0.2, 0.3] })"),
       {"bad.tuple:3:", "out of range", "1e400"}},
      {"T zero",
       ThirdRecord(R"({ "T": 0, "phi_l": 1, "phi_r": 2, "sm": [0.1, 0.2, 0.3] })"),
       {"bad.tuple:3:", "record 3", "T must be positive and finite, got 0"}},
      {"T negative",
       ThirdRecord(R"({ "T": -0.5, "phi_l": 1, "phi_r": 2, "sm": [0.1, 0.2, 0.3] })"),
       {"bad.tuple:3:", "record 3", "T must be positive and finite, got -0.5"}},
      {"sm of 2",
       ThirdRecord(R"({ "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0.1, 0.2] })"),
       {"bad.tuple:3:", "record 3", "3 numbers", "got 2"}},
      {"sm of 4",
       ThirdRecord(R"({ "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0.1, 0.2, 0.3, 0.4] })"),
       {"bad.tuple:3:", "record 3", "3 numbers", "got 4"}},
      {"sm empty",
       ThirdRecord(R"({ "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [] })"),
       {"bad.tuple:3:", "3 numbers", "got 0"}},
      {"sm not an array",
       ThirdRecord(R"({ "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": 0.1 })"),
       {"bad.tuple:3:", "record 3", "sm must be an array"}},
      {"T an array",
       ThirdRecord(R"({ "T": [0.5], "phi_l": 1, "phi_r": 2, "sm": [0.1, 0.2, 0.3] })"),
       {"bad.tuple:3:", "T must be a number"}},
      {"quoted number",
       ThirdRecord(R"({ "T": "0.5", "phi_l": 1, "phi_r": 2, "sm": [0.1, 0.2, 0.3] })"),
       {"bad.tuple:3:", "record 3", "value of T is not a number", "\"0.5\""}},
      {"null",
       ThirdRecord(R"({ "T": 0.5, "phi_l": null, "phi_r": 2, "sm": [0.1, 0.2, 0.3] })"),
       {"bad.tuple:3:", "value of phi_l is not a number", "null"}},
      {"trailing letters",
       ThirdRecord(R"({ "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0.1, 0.2x, 0.3] })"),
       {"bad.tuple:3:", "value of sm is not a number", "0.2x"}},
      {"garbage between records",
       ThirdRecord(std::string("xyz ") + kRecord),
       {"bad.tuple:3:", "after record 2", "between records", "xyz"}},
      {"comma between records",
       std::string(kRecord) + ",\n" + kRecord,
       {"bad.tuple:1:", "after record 1", "between records"}},
      {"top-level array", std::string("[") + kRecord + "]", {"bad.tuple:1:", "between records"}},
      {"unknown key",
       ThirdRecord(R"({ "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0.1, 0.2, 0.3], "foo": 1 })"),
       {"bad.tuple:3:", "record 3", "unknown key \"foo\""}},
      {"missing key",
       ThirdRecord(R"({ "T": 0.5, "phi_l": 1, "sm": [0.1, 0.2, 0.3] })"),
       {"bad.tuple:3:", "record 3", "missing key \"phi_r\""}},
      {"duplicate key",
       ThirdRecord(R"({ "T": 0.5, "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0.1, 0.2, 0.3] })"),
       {"bad.tuple:3:", "record 3", "duplicate key \"T\""}},
      {"missing colon",
       ThirdRecord(R"({ "T" 0.5, "phi_l": 1, "phi_r": 2, "sm": [0.1, 0.2, 0.3] })"),
       {"bad.tuple:3:", "expected ':'"}},
      {"missing comma",
       ThirdRecord(R"({ "T": 0.5 "phi_l": 1, "phi_r": 2, "sm": [0.1, 0.2, 0.3] })"),
       {"bad.tuple:3:", "expected ',' or '}'"}},
      {"unquoted key",
       ThirdRecord(R"({ T: 0.5, "phi_l": 1, "phi_r": 2, "sm": [0.1, 0.2, 0.3] })"),
       {"bad.tuple:3:", "expected a quoted key"}},
      {"t in some records only",
       R"({ "t": 0, "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0, 0, 0] })"
       "\n" +
           std::string(kRecord),
       {"bad.tuple:2:", "record 2", "every record or in none"}},
      {"t decreasing",
       R"({ "t": 5, "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0, 0, 0] }
          { "t": 4, "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0, 0, 0] })",
       {"bad.tuple:2:", "record 2", "non-decreasing"}},
      {"t overlaps",
       R"({ "t": 5, "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0, 0, 0] }
          { "t": 5.4, "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0, 0, 0] })",
       {"bad.tuple:2:", "record 2", "overlaps the previous interval"}},
      {"t NaN",
       R"({ "t": NaN, "T": 0.5, "phi_l": 1, "phi_r": 2, "sm": [0, 0, 0] })",
       {"bad.tuple:1:", "record 1", "t must be finite"}},
  };
  for (const ErrorCase& c : cases) {
    SCOPED_TRACE(c.name);
    const StatusOr<LaserLog> log = ParseLaserTuples(c.text, "bad.tuple");
    ASSERT_FALSE(log.ok());
    for (const std::string& part : c.parts) {
      EXPECT_NE(log.message().find(part), std::string::npos)
          << "message: " << log.message() << "\nlacks: " << part;
    }
  }
}

TEST(LaserCsvTest, ColumnsInAnyOrderWithExtrasSpacesAndCrLf) {
  const std::string text =
      "# written by hand\r\n"
      "\r\n"
      " sm_theta , quality, phi_r,T,sm_y, phi_l ,sm_x\r\n"
      "0.3, good, 2, 0.5, 0.2, 1, 0.1\r\n"
      "\r\n"
      "# a comment between rows\r\n"
      "-0.3,bad,+4,0.25,-0.2,-1e-3,-0.1\r\n";
  const StatusOr<LaserLog> log = ParseLaserCsv(text, "x.csv");
  ASSERT_TRUE(log.ok()) << log.message();
  EXPECT_FALSE(log->has_timestamps);
  ASSERT_EQ(log->intervals.size(), 2u);
  const LaserInterval& a = log->intervals[0];
  EXPECT_EQ(a.duration_s, 0.5);
  EXPECT_EQ(a.left_speed, 1.0);
  EXPECT_EQ(a.right_speed, 2.0);
  EXPECT_EQ(a.sensor_motion, Pose2d(0.1, 0.2, 0.3));
  EXPECT_EQ(a.start_s, 0.0);
  EXPECT_EQ(a.line, 4);
  EXPECT_EQ(a.record, 1);
  const LaserInterval& b = log->intervals[1];
  EXPECT_EQ(b.duration_s, 0.25);
  EXPECT_EQ(b.left_speed, -1e-3);
  EXPECT_EQ(b.right_speed, 4.0);
  EXPECT_EQ(b.sensor_motion, Pose2d(-0.1, -0.2, -0.3));
  EXPECT_EQ(b.start_s, 0.5);
  EXPECT_EQ(b.line, 7);
  EXPECT_EQ(b.record, 2);
}

TEST(LaserCsvTest, StartTimesAndGaps) {
  const std::string text =
      "T,phi_l,phi_r,sm_x,sm_y,sm_theta,t\n"
      "0.5,1,2,0,0,0,100\n"
      "0.5,1,2,0,0,0,100.5\n"
      "0.5,1,2,0,0,0,102\n"
      "0.5,1,2,0,0,0,102.5000001\n";
  const StatusOr<LaserLog> log = ParseLaserCsv(text, "x.csv");
  ASSERT_TRUE(log.ok()) << log.message();
  EXPECT_TRUE(log->has_timestamps);
  ASSERT_EQ(log->intervals.size(), 4u);
  EXPECT_EQ(log->intervals[2].start_s, 102.0);
  EXPECT_FALSE(log->intervals[1].gap_before);
  EXPECT_TRUE(log->intervals[2].gap_before);
  EXPECT_FALSE(log->intervals[3].gap_before);
}

TEST(LaserCsvTest, ErrorsNameFileLineRecordAndProblem) {
  const std::string header = "T,phi_l,phi_r,sm_x,sm_y,sm_theta\n";
  const std::string row = "0.5,1,2,0.1,0.2,0.3\n";
  const std::string header_t = "t,T,phi_l,phi_r,sm_x,sm_y,sm_theta\n";
  const std::vector<ErrorCase> cases = {
      {"empty", "", {"bad.csv", "holds no records"}},
      {"comments only", "# nothing\n\n", {"bad.csv", "holds no records"}},
      {"header only", header, {"bad.csv", "holds no records"}},
      {"duplicated name",
       "T,phi_l,phi_r,sm_x,sm_y,sm_theta,T\n" + row,
       {"bad.csv:1:", "duplicated", "'T'"}},
      {"duplicated ignored name",
       "T,phi_l,phi_r,sm_x,sm_y,sm_theta,q,q\n",
       {"bad.csv:1:", "duplicated", "'q'"}},
      {"missing name", "T,phi_l,phi_r,sm_x,sm_y\n", {"bad.csv:1:", "lacks", "sm_theta"}},
      {"missing names", "# c\nphi_l,phi_r,sm_x,sm_y\n", {"bad.csv:2:", "T, sm_theta"}},
      {"too few fields",
       header + row + "0.5,1,2,0.1,0.2\n",
       {"bad.csv:3:", "record 2", "5 fields", "header has 6"}},
      {"too many fields",
       header + row + "0.5,1,2,0.1,0.2,0.3,9\n",
       {"bad.csv:3:", "record 2", "7 fields"}},
      {"non-numeric",
       header + row + "0.5,abc,2,0.1,0.2,0.3\n",
       {"bad.csv:3:", "record 2", "phi_l is not a number", "abc"}},
      {"trailing letters", header + "0.5,1,2,0.1,0.2,0.3x\n", {"bad.csv:2:", "not a number"}},
      {"NaN", header + row + "0.5,1,NaN,0.1,0.2,0.3\n", {"bad.csv:3:", "phi_r must be finite"}},
      {"inf", header + "0.5,1,2,inf,0.2,0.3\n", {"bad.csv:2:", "record 1", "sm_x must be finite"}},
      {"Infinity", header + "0.5,1,2,0,-Infinity,0.3\n", {"bad.csv:2:", "sm_y must be finite"}},
      {"T negative",
       header + row + row + "-0.5,1,2,0.1,0.2,0.3\n",
       {"bad.csv:4:", "record 3", "T must be positive and finite, got -0.5"}},
      {"empty required", header + "0.5,,2,0.1,0.2,0.3\n", {"bad.csv:2:", "empty value for phi_l"}},
      {"t in some rows only",
       header_t + "0,0.5,1,2,0,0,0\n,0.5,1,2,0,0,0\n",
       {"bad.csv:3:", "record 2", "every record or in none"}},
      {"t decreasing",
       header_t + "5,0.5,1,2,0,0,0\n4,0.5,1,2,0,0,0\n",
       {"bad.csv:3:", "record 2", "non-decreasing"}},
      {"t overlaps",
       header_t + "5,0.5,1,2,0,0,0\n5.3,0.5,1,2,0,0,0\n",
       {"bad.csv:3:", "record 2", "overlaps the previous interval"}},
  };
  for (const ErrorCase& c : cases) {
    SCOPED_TRACE(c.name);
    const StatusOr<LaserLog> log = ParseLaserCsv(c.text, "bad.csv");
    ASSERT_FALSE(log.ok());
    for (const std::string& part : c.parts) {
      EXPECT_NE(log.message().find(part), std::string::npos)
          << "message: " << log.message() << "\nlacks: " << part;
    }
  }
}

TEST_F(LaserLogIoTest, TuplesRoundTripWithoutAndWithStartTimes) {
  std::mt19937 rng(7);
  for (const bool with_t : {false, true}) {
    SCOPED_TRACE(with_t ? "with t" : "without t");
    const LaserLog log = RandomLog(300, with_t, &rng);
    const std::string path = Path("log.tuple");
    ASSERT_TRUE(WriteLaserTuples(log, path).ok());
    const StatusOr<LaserLog> read = ReadLaserLog(path);
    ASSERT_TRUE(read.ok()) << read.message();
    EXPECT_EQ(read->source, path);
    ExpectSameValues(log, *read, false);
    EXPECT_EQ(read->intervals.back().line, 300);
    EXPECT_EQ(read->intervals.back().record, 300);
  }
}

TEST_F(LaserLogIoTest, CsvRoundTrip) {
  std::mt19937 rng(8);
  LaserLog log = RandomLog(300, true, &rng);
  const std::string path = Path("log.csv");
  ASSERT_TRUE(WriteLaserCsv(log, path).ok());
  std::ifstream in(path);
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "t,T,phi_l,phi_r,sm_x,sm_y,sm_theta");
  StatusOr<LaserLog> read = ReadLaserLog(path, LaserFormat::kCsv);
  ASSERT_TRUE(read.ok()) << read.message();
  ExpectSameValues(log, *read, false);
  EXPECT_EQ(read->intervals[0].line, 2);

  // A log without timestamps comes back with its summed start times as t.
  log = RandomLog(50, false, &rng);
  ASSERT_TRUE(WriteLaserCsv(log, path).ok());
  read = ReadLaserLog(path);
  ASSERT_TRUE(read.ok()) << read.message();
  log.has_timestamps = true;
  ExpectSameValues(log, *read, false);
}

TEST_F(LaserLogIoTest, ReadLaserLogDetectsTheFormat) {
  const std::string tuples = Write("a.txt", "\n  \t" + std::string(kRecord));
  const std::string csv = Write("b.txt", "T,phi_l,phi_r,sm_x,sm_y,sm_theta\n0.5,1,2,3,4,5\n");
  StatusOr<LaserLog> log = ReadLaserLog(tuples);
  ASSERT_TRUE(log.ok()) << log.message();
  EXPECT_EQ(log->intervals.size(), 1u);
  log = ReadLaserLog(csv);
  ASSERT_TRUE(log.ok()) << log.message();
  EXPECT_EQ(log->intervals[0].sensor_motion, Pose2d(3, 4, 5));
  // Forcing the wrong format fails with the parser's message.
  ExpectError(ReadLaserLog(csv, LaserFormat::kTuples), {csv + ":1:", "between records"});
  ExpectError(ReadLaserLog(tuples, LaserFormat::kCsv), {tuples + ":2:", "lacks"});
  ExpectError(ReadLaserLog(tuples, LaserFormat::kStream), {tuples, "directory"});
  ExpectError(ReadLaserLog(dir_.string(), LaserFormat::kCsv), {dir_.string(), "directory"});
  ExpectError(ReadLaserLog(Path("missing.tuple")), {Path("missing.tuple"), "no such file"});
  ExpectError(ReadLaserLog(Write("empty.csv", "")), {"empty.csv", "holds no records"});
}

TEST_F(LaserLogIoTest, WritersReportErrors) {
  std::mt19937 rng(9);
  LaserLog log = RandomLog(3, false, &rng);
  const std::string unwritable = Path("no/such/dir/log.tuple");
  EXPECT_NE(WriteLaserTuples(log, unwritable).message().find(unwritable), std::string::npos);
  EXPECT_FALSE(WriteLaserCsv(log, unwritable).ok());
  log.intervals[1].left_speed = std::nan("");
  const Status status = WriteLaserTuples(log, Path("nan.tuple"));
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.message().find("interval 2"), std::string::npos) << status.message();
  EXPECT_NE(status.message().find("non-finite"), std::string::npos) << status.message();
  EXPECT_FALSE(WriteLaserCsv(log, Path("nan.csv")).ok());
}

// ---------------------------------------------------------------------------------------------
// Raw streams.

// Wheel speeds constant over blocks of encoder periods; the angles are their exact integral.
// Wheels at constant accelerations, encoders polled at 10 Hz: the stream reader's cubic between
// polls reproduces the angles exactly (the speeds never change sign).
struct WheelSignal {
  std::vector<double> times;
  double left_speed = 1.0, left_acceleration = 0.15;  // rad/s, rad/s².
  double right_speed = -0.4, right_acceleration = -0.08;

  double Angle(double t, bool left) const {
    return left ? left_speed * t + 0.5 * left_acceleration * t * t
                : right_speed * t + 0.5 * right_acceleration * t * t;
  }
  // ∫ speed over [a, b], independent of the reader's code.
  double Rotation(double a, double b, bool left) const { return Angle(b, left) - Angle(a, left); }

  std::vector<EncoderSample> Samples() const {
    std::vector<EncoderSample> samples;
    for (double t : times) samples.push_back(EncoderSample{t, Angle(t, true), Angle(t, false)});
    return samples;
  }
};

// 10 Hz over [0, duration].
WheelSignal MakeWheelSignal(double duration) {
  WheelSignal signal;
  const int n = static_cast<int>(std::lround(duration * 10.0));
  for (int i = 0; i <= n; ++i) signal.times.push_back(i / 10.0);
  return signal;
}

std::vector<StampedPose> IrregularPoses(double begin, double end, std::mt19937* rng) {
  std::uniform_real_distribution<double> step(0.05, 0.4);
  std::uniform_real_distribution<double> xy(-5.0, 5.0);
  std::uniform_real_distribution<double> angle(-3.1, 3.1);
  std::vector<StampedPose> poses;
  for (double t = begin; t < end; t += step(*rng)) {
    poses.push_back(StampedPose{t, Pose2d(xy(*rng), xy(*rng), angle(*rng))});
  }
  return poses;
}

void ExpectIntervalMatchesSignal(const LaserInterval& interval, const WheelSignal& signal,
                                 const StampedPose& a, const StampedPose& b) {
  const double ta = a.t_s;
  const double tb = b.t_s;
  EXPECT_EQ(interval.start_s, ta);
  EXPECT_EQ(interval.duration_s, tb - ta);
  EXPECT_NEAR(interval.left_speed * interval.duration_s, signal.Rotation(ta, tb, true), 1e-12);
  EXPECT_NEAR(interval.right_speed * interval.duration_s, signal.Rotation(ta, tb, false), 1e-12);
  Pose2d expected = Between(a.world_T_sensor, b.world_T_sensor);
  expected(2) = WrapAngle(expected(2));
  EXPECT_NEAR((interval.sensor_motion - expected).norm(), 0.0, 1e-15);
  EXPECT_GT(interval.sensor_motion(2), -M_PI);
  EXPECT_LE(interval.sensor_motion(2), M_PI);

  // One step per encoder period cut by the interval ends.
  std::vector<double> cuts = {ta};
  for (double t : signal.times) {
    if (t > ta && t < tb) cuts.push_back(t);
  }
  cuts.push_back(tb);
  if (cuts.size() == 2) {
    EXPECT_TRUE(interval.steps.empty());
    return;
  }
  ASSERT_EQ(interval.steps.size(), cuts.size() - 1);
  double duration = 0.0;
  for (size_t s = 0; s + 1 < cuts.size(); ++s) {
    const WheelStep& step = interval.steps[s];
    EXPECT_NEAR(step.duration_s, cuts[s + 1] - cuts[s], 1e-15);
    EXPECT_NEAR(step.left_rad, signal.Rotation(cuts[s], cuts[s + 1], true), 1e-12);
    EXPECT_NEAR(step.right_rad, signal.Rotation(cuts[s], cuts[s + 1], false), 1e-12);
    duration += step.duration_s;
  }
  EXPECT_NEAR(duration, interval.duration_s, 1e-12);
}

TEST(LaserStreamTest, IntegratesEncoderSamplesIntoSteps) {
  std::mt19937 rng(3);
  const WheelSignal signal = MakeWheelSignal(10.0);
  // Starts before and ends after the encoder span: those poses are dropped.
  std::vector<StampedPose> poses = IrregularPoses(-0.3, 10.35, &rng);
  // One pose exactly on an encoder sample, one interval shorter than an encoder period (pose
  // periods are at least 0.05 s, so the order is kept).
  poses[10].t_s = std::round(poses[10].t_s * 10.0) / 10.0;
  poses[11].t_s = poses[10].t_s + 0.005;
  ASSERT_GT(poses.back().t_s, 10.0);
  const StatusOr<LaserLog> log = LaserLogFromStreams(signal.Samples(), poses, "sim");
  ASSERT_TRUE(log.ok()) << log.message();
  EXPECT_TRUE(log->has_timestamps);
  EXPECT_EQ(log->source, "sim");

  size_t first = 0;
  while (poses[first].t_s < 0.0) ++first;
  size_t last = poses.size();
  while (poses[last - 1].t_s > 10.0) --last;
  ASSERT_GT(first, 0u);
  ASSERT_LT(last, poses.size());
  ASSERT_EQ(log->intervals.size(), last - first - 1);
  for (size_t k = 0; k < log->intervals.size(); ++k) {
    SCOPED_TRACE("interval " + std::to_string(k));
    const LaserInterval& interval = log->intervals[k];
    EXPECT_EQ(interval.record, static_cast<int>(first + k) + 1);
    EXPECT_EQ(interval.line, 0);
    EXPECT_FALSE(interval.gap_before);
    ExpectIntervalMatchesSignal(interval, signal, poses[first + k], poses[first + k + 1]);
  }
}

TEST(LaserStreamTest, EncoderGapDropsIntervalsAndMarksTheNext) {
  const WheelSignal signal = MakeWheelSignal(8.0);
  std::vector<EncoderSample> odometry;
  for (const EncoderSample& s : signal.Samples()) {
    if (!(s.t_s > 3.0 && s.t_s < 3.6)) odometry.push_back(s);  // 0.6 s > 5 × 0.1 s.
  }
  std::vector<StampedPose> poses;
  for (int k = 0; k < 30; ++k) {
    poses.push_back(StampedPose{0.1 + 0.25 * k, Pose2d(0.1 * k, 0.0, 0.05 * k)});
  }
  const StatusOr<LaserLog> log = LaserLogFromStreams(odometry, poses, "sim");
  ASSERT_TRUE(log.ok()) << log.message();
  size_t kept = 0;
  bool expect_gap = false;
  for (size_t k = 0; k + 1 < poses.size(); ++k) {
    const double ta = poses[k].t_s;
    const double tb = poses[k + 1].t_s;
    if (ta < 3.6 && tb > 3.0) {
      expect_gap = true;
      continue;
    }
    ASSERT_LT(kept, log->intervals.size());
    const LaserInterval& interval = log->intervals[kept++];
    SCOPED_TRACE("record " + std::to_string(interval.record));
    EXPECT_EQ(interval.start_s, ta);
    EXPECT_EQ(interval.gap_before, expect_gap);
    expect_gap = false;
    // Interpolation outside the gap still matches the true signal.
    EXPECT_NEAR(interval.left_speed * interval.duration_s, signal.Rotation(ta, tb, true), 1e-12);
  }
  EXPECT_EQ(kept, log->intervals.size());
  EXPECT_LT(kept, poses.size() - 1);
}

// A scan matcher's chain that broke: the poses of the two segments have no displacement between
// them, so no interval (nor latent-time sample pair) spans the break.
TEST(LaserStreamTest, PoseSegmentsAreNotJoined) {
  const std::vector<EncoderSample> odometry = MakeWheelSignal(8.0).Samples();
  std::vector<StampedPose> poses;
  for (int k = 0; k < 20; ++k) {
    StampedPose p{0.1 + 0.25 * k, Pose2d(0.1 * k, 0.0, 0.05 * k)};
    p.segment = k < 8 ? 0 : 3;
    poses.push_back(p);
  }
  const StatusOr<LaserLog> log = LaserLogFromStreams(odometry, poses, "sim");
  ASSERT_TRUE(log.ok()) << log.message();
  ASSERT_EQ(log->intervals.size(), poses.size() - 2);
  for (const LaserInterval& interval : log->intervals) {
    EXPECT_NE(interval.start_s, poses[7].t_s);
    EXPECT_EQ(interval.gap_before, interval.start_s == poses[8].t_s);
  }
  EXPECT_EQ(log->streams.sensor_poses[7].segment, 0);
  EXPECT_EQ(log->streams.sensor_poses[8].segment, 3);
  const StatusOr<StreamSamples> samples = BuildStreamSamples(odometry, poses, "sim");
  ASSERT_TRUE(samples.ok()) << samples.message();
  EXPECT_EQ(samples->interval_start.size(), poses.size() - 2);
  for (const int k : samples->interval_start) EXPECT_NE(k, 7);
}

TEST(LaserStreamTest, Errors) {
  const std::vector<EncoderSample> odometry = MakeWheelSignal(2.0).Samples();
  const std::vector<StampedPose> poses = {{0.5, Pose2d::Zero()}, {1.0, Pose2d::Zero()}};
  ExpectError(LaserLogFromStreams(odometry, {{3.0, Pose2d::Zero()}, {4.0, Pose2d::Zero()}}, "s"),
              {"s (sensor poses)", "no pair of sensor poses", "time span"});
  ExpectError(LaserLogFromStreams({odometry[0]}, poses, "s"), {"s (odometry)", "at least 2"});
  ExpectError(LaserLogFromStreams(odometry, {poses[0]}, "s"), {"s (sensor poses)", "at least 2"});
  std::vector<EncoderSample> bad = odometry;
  bad[4].t_s = bad[3].t_s;
  ExpectError(LaserLogFromStreams(bad, poses, "s"),
              {"s (odometry): record 4 and record 5 share t=", "differ in left"});
  bad = odometry;
  bad[4].t_s = bad[2].t_s;
  ExpectError(LaserLogFromStreams(bad, poses, "s"), {"sample 5", "strictly increasing"});
  bad = odometry;
  bad[6].right_rad = std::nan("");
  ExpectError(LaserLogFromStreams(bad, poses, "s"), {"sample 7", "finite"});
  std::vector<StampedPose> bad_poses = {{1.0, Pose2d::Zero()}, {0.5, Pose2d::Zero()}};
  ExpectError(LaserLogFromStreams(odometry, bad_poses, "s"), {"pose 2", "strictly increasing"});
  bad_poses = {{0.5, Pose2d(0, INFINITY, 0)}, {1.0, Pose2d::Zero()}};
  ExpectError(LaserLogFromStreams(odometry, bad_poses, "s"), {"pose 1", "finite"});

  // Every interval spans a gap.
  std::vector<EncoderSample> gappy;
  for (const EncoderSample& s : odometry) {
    if (s.t_s < 0.5 || s.t_s > 1.5) gappy.push_back(s);
  }
  ExpectError(
      LaserLogFromStreams(gappy, {{0.4, Pose2d::Zero()}, {1.6, Pose2d(0.1, 0.0, 0.0)}}, "s"),
      {"s:", "no interval remains", "gap"});
}

TEST_F(LaserLogIoTest, StreamRoundTripThroughFiles) {
  std::mt19937 rng(4);
  const WheelSignal signal = MakeWheelSignal(6.0);
  const std::vector<EncoderSample> odometry = signal.Samples();
  const std::vector<StampedPose> poses = IrregularPoses(0.01, 5.9, &rng);
  const std::string directory = Path("new/stream");  // Created by the writer.
  ASSERT_TRUE(WriteLaserStream(odometry, poses, directory).ok());
  const StatusOr<LaserLog> expected = LaserLogFromStreams(odometry, poses, directory);
  ASSERT_TRUE(expected.ok()) << expected.message();
  for (const LaserFormat format : {LaserFormat::kAuto, LaserFormat::kStream}) {
    const StatusOr<LaserLog> read = ReadLaserLog(directory, format);
    ASSERT_TRUE(read.ok()) << read.message();
    EXPECT_EQ(read->source, directory);
    ExpectSameValues(*expected, *read, true);
    for (size_t k = 0; k < read->intervals.size(); ++k) {
      EXPECT_EQ(read->intervals[k].line, static_cast<int>(k) + 2);  // After the header.
      ExpectIntervalMatchesSignal(read->intervals[k], signal, poses[k], poses[k + 1]);
    }
  }

  // And a stream log survives the tuple writer, gaps and all (steps are not stored).
  const std::string tuples = Path("stream.tuple");
  ASSERT_TRUE(WriteLaserTuples(*expected, tuples).ok());
  const StatusOr<LaserLog> back = ReadLaserLog(tuples);
  ASSERT_TRUE(back.ok()) << back.message();
  ExpectSameValues(*expected, *back, false);
}

TEST_F(LaserLogIoTest, StreamFileErrorsNameFileAndLine) {
  const std::string odometry_ok = "t,left,right\n0,0,0\n0.02,0.1,0.1\n0.04,0.2,0.2\n0.06,0.3,0.3\n";
  const std::string poses_ok = "t,x,y,theta\n0.01,0,0,0\n0.05,0.1,0,0\n";
  struct StreamCase {
    const char* name;
    std::string odometry;
    std::string poses;
    std::vector<std::string> parts;
  };
  const std::vector<StreamCase> cases = {
      {"odometry time goes back",
       "t,left,right\n0,0,0\n0.02,0.1,0.1\n0.01,0.2,0.2\n",
       poses_ok,
       {"odometry.csv:4:", "strictly increasing"}},
      {"pose time repeats with other values",
       odometry_ok,
       "t,x,y,theta\n0.01,0,0,0\n\n0.01,0.1,0,0\n",
       {"sensor_poses.csv: line 2 and line 4 share t=0.01 but differ in x"}},
      {"pose time goes back",
       odometry_ok,
       "t,x,y,theta\n0.02,0,0,0\n0.05,0,0,0\n0.01,0.1,0,0\n",
       {"sensor_poses.csv:4:", "strictly increasing", "(line 3)"}},
      {"NaN pose",
       odometry_ok,
       "t,x,y,theta\n0.01,0,0,0\n0.05,nan,0,0\n",
       {"sensor_poses.csv:3:", "x must be finite"}},
      {"missing column", "t,left\n0,0\n0.02,0.1\n", poses_ok, {"odometry.csv:1:", "right"}},
      {"no samples", "t,left,right\n", poses_ok, {"odometry.csv", "at least 2"}},
      {"bad field count",
       odometry_ok,
       "t,x,y,theta\n0.01,0,0\n",
       {"sensor_poses.csv:2:", "3 fields"}},
      {"outside the span",
       odometry_ok,
       "t,x,y,theta\n1,0,0,0\n2,0,0,0\n",
       {"sensor_poses.csv", "time span"}},
  };
  for (const StreamCase& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path directory = dir_ / c.name;
    fs::create_directories(directory);
    std::ofstream(directory / "odometry.csv") << c.odometry;
    std::ofstream(directory / "sensor_poses.csv") << c.poses;
    const StatusOr<LaserLog> log = ReadLaserStream(directory.string());
    ASSERT_FALSE(log.ok());
    for (const std::string& part : c.parts) {
      EXPECT_NE(log.message().find(part), std::string::npos)
          << "message: " << log.message() << "\nlacks: " << part;
    }
  }
  const fs::path lonely = dir_ / "lonely";
  fs::create_directories(lonely);
  std::ofstream(lonely / "odometry.csv") << odometry_ok;
  ExpectError(ReadLaserStream(lonely.string()), {"sensor_poses.csv", "no such file"});
  ExpectError(ReadLaserStream(Path("absent")), {"absent", "not a directory"});
}

// ---------------------------------------------------------------------------------------------
// The published recordings.

std::string CensiFile(const std::string& name) {
  return (fs::path(CALIB_CENSI_DATA_DIR) / name).string();
}

TEST(CensiDataTest, ReadsThePublishedTupleFiles) {
  if (!fs::exists(CensiFile("l90.tuple"))) {
    GTEST_SKIP() << "The Censi et al. 2013 tuple files are not in " << CALIB_CENSI_DATA_DIR
                 << " (set CALIB_CENSI_DATA_DIR to their folder to run this test)";
  }
  const struct {
    const char* name;
    size_t records;
  } files[] = {{"l90.tuple", 3295}, {"lmov.tuple", 4345}, {"lstraight.tuple", 4396}};
  for (const auto& file : files) {
    SCOPED_TRACE(file.name);
    const auto start = std::chrono::steady_clock::now();
    const StatusOr<LaserLog> log = ReadLaserLog(CensiFile(file.name));
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    ASSERT_TRUE(log.ok()) << log.message();
    EXPECT_EQ(log->intervals.size(), file.records);
    EXPECT_FALSE(log->has_timestamps);
    std::printf("[ info     ] %s: %zu records read in %.2f ms\n", file.name, log->intervals.size(),
                seconds * 1e3);
  }

  // l90.tuple: line 1082 holds records 1082 and 1083 with no newline between them.
  const StatusOr<LaserLog> l90 = ReadLaserLog(CensiFile("l90.tuple"), LaserFormat::kTuples);
  ASSERT_TRUE(l90.ok()) << l90.message();
  EXPECT_EQ(l90->intervals[1081].line, 1082);
  EXPECT_EQ(l90->intervals[1082].line, 1082);
  EXPECT_EQ(l90->intervals[1082].record, 1083);
  EXPECT_EQ(l90->intervals[1083].line, 1083);

  const StatusOr<LaserLog> l90_0 = ReadLaserLog(CensiFile("l90_0.tuple"));
  ASSERT_TRUE(l90_0.ok()) << l90_0.message();
  const LaserInterval& first = l90_0->intervals.front();
  EXPECT_EQ(first.duration_s, 7.943960e-01);
  EXPECT_EQ(first.left_speed, 1.401765e-01);
  EXPECT_EQ(first.right_speed, -1.373157e-01);
  EXPECT_EQ(first.sensor_motion, Pose2d(1.092608e-03, -5.089714e-04, -2.748851e-02));
  // The subset holds every third record of the full file, starting at the first.
  ASSERT_EQ(l90_0->intervals.size(), (l90->intervals.size() + 2) / 3);
  for (size_t k = 0; k < l90_0->intervals.size(); ++k) {
    ASSERT_EQ(l90_0->intervals[k].sensor_motion, l90->intervals[3 * k].sensor_motion) << k;
  }
}

// The reader must take well under a second per million records.
TEST(LaserTuplesTest, ParsesManyRecordsQuickly) {
  const int n = 200000;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> value(-1.0, 1.0);
  std::string text;
  text.reserve(static_cast<size_t>(n) * 130);
  char buffer[256];
  for (int k = 0; k < n; ++k) {
    std::snprintf(buffer, sizeof(buffer),
                  "{ \"T\": %e, \"phi_l\": %e, \"phi_r\": %e, \"sm\": [ %e, %e, %e ] }\n",
                  0.8 + 0.01 * value(rng), value(rng), value(rng), 1e-3 * value(rng),
                  1e-3 * value(rng), 0.2 * value(rng));
    text += buffer;
  }
  const auto start = std::chrono::steady_clock::now();
  const StatusOr<LaserLog> log = ParseLaserTuples(text, "big.tuple");
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  ASSERT_TRUE(log.ok()) << log.message();
  EXPECT_EQ(log->intervals.size(), static_cast<size_t>(n));
  EXPECT_EQ(log->intervals.back().line, n);
  std::printf("[ info     ] %d records (%.1f MB) parsed in %.1f ms: %.0f ms per million\n", n,
              text.size() / 1e6, seconds * 1e3, seconds * 1e3 * 1e6 / n);
}

// A long text (> 4 MB) is parsed in two halves at once: the log is the one a single pass reads,
// with the lines and records of the second half numbered on from the first's, the checks across
// records (duplicates, gaps) applied across the split, and an error in the second half reported
// at its own line.
double HalvesStart(int value) { return 0.5 * value + (value / 777) * 10.0; }

std::string HalvesText(int n, int bad_record) {
  std::string text;
  for (int k = 1; k <= n; ++k) {
    // Every 1000th record repeats the one before (dropped); every 3rd spans two lines; t jumps
    // (a gap) every 777th.
    const int value = k % 1000 == 0 ? k - 1 : k;
    const std::string phi_l = k == bad_record ? "x" : std::to_string(1.0 + 1e-6 * value);
    text += "{\"t\": " + std::to_string(HalvesStart(value)) + ", \"T\": 0.5," +
            (k % 3 == 0 ? "\n" : " ") + "\"phi_l\": " + phi_l +
            ", \"phi_r\": 1.2, \"sm\": [0.05, 0.001, 0.01]}\n";
  }
  return text;
}

TEST(LaserTuplesInHalvesTest, AreTheLogOfOnePass) {
  const int n = 60000;  // About 6 MB.
  const std::string text = HalvesText(n, 0);
  ASSERT_GT(text.size(), size_t{4} << 20);
  const StatusOr<LaserLog> log = ParseLaserTuples(text, "long.tuple");
  ASSERT_TRUE(log.ok()) << log.message();
  ASSERT_EQ(log->intervals.size(), static_cast<size_t>(n - n / 1000));
  int line = 1, gaps = 0;
  size_t i = 0;
  double previous_end = 0.0;
  for (int k = 1; k <= n; ++k) {
    if (k % 1000 != 0) {
      const LaserInterval& interval = log->intervals[i++];
      ASSERT_EQ(interval.record, k);
      ASSERT_EQ(interval.line, line);
      ASSERT_DOUBLE_EQ(interval.left_speed, 1.0 + 1e-6 * k);
      // A gap after each jump of t and after each dropped repeat.
      ASSERT_EQ(interval.gap_before, k > 1 && HalvesStart(k) > previous_end + 1e-3) << k;
      previous_end = HalvesStart(k) + 0.5;
      gaps += interval.gap_before;
    }
    line += k % 3 == 0 ? 2 : 1;
  }
  EXPECT_GT(gaps, 100);
  ASSERT_EQ(log->warnings.size(), 1u);
  EXPECT_NE(log->warnings[0].find(std::to_string(n / 1000) +
                                  " exact duplicate record(s) dropped (record 1000, 2000,"),
            std::string::npos)
      << log->warnings[0];
}

TEST(LaserTuplesInHalvesTest, AnErrorInTheSecondHalfNamesItsLine) {
  const int n = 60000, bad = 45001;  // 45001 = 3·15000 + 1: lines 1 … 60000 before it.
  const StatusOr<LaserLog> log = ParseLaserTuples(HalvesText(n, bad), "long.tuple");
  ASSERT_FALSE(log.ok());
  EXPECT_NE(log.message().find("long.tuple:60001: record 45001: "), std::string::npos)
      << log.message();
  EXPECT_NE(log.message().find("phi_l"), std::string::npos) << log.message();
}

}  // namespace
}  // namespace calib
