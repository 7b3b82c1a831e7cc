// Hostile inputs cost the readers an error, not the machine: bounded lines, records and columns,
// binary files refused before parsing, no counter that overflows, no length field trusted.
#include <calib/core/bag/robot_messages.h>
#include <calib/core/bearing/bearing_log_io.h>
#include <calib/core/csv.h>
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/text_file.h>
#include <calib/core/timing/stamp_timing.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <climits>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <new>
#include <string>
#include <thread>
#include <type_traits>
#include <vector>

namespace calib {
namespace {

namespace fs = std::filesystem;

const std::string kHeader = "T,phi_l,phi_r,sm_x,sm_y,sm_theta\n";
const std::string kRow = "0.5,1,1.2,0.05,0.001,0.01\n";

void ExpectMessage(const Status& status, const std::vector<std::string>& parts) {
  ASSERT_FALSE(status.ok());
  for (const std::string& part : parts) {
    EXPECT_NE(status.message().find(part), std::string::npos)
        << "message: " << status.message() << "\nlacks: " << part;
  }
}

template <typename T>
Status StatusOf(const StatusOr<T>& s) {
  return s.ok() ? Status::Ok() : s.status();
}

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A fresh directory under the system's temporary one, removed with the fixture.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "calib_limits_XXXXXX").string();
    path_ = mkdtemp(pattern.data());
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  std::string operator/(const std::string& name) const { return (fs::path(path_) / name).string(); }

 private:
  std::string path_;
};

long MaxRssKb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

TEST(ReaderLimitsTest, HeaderOfTwoHundredThousandColumnsIsRefusedFast) {
  std::string header = "T,phi_l,phi_r,sm_x,sm_y,sm_theta";
  for (int i = 0; i < 200000; ++i) header += ",c" + std::to_string(i);
  const auto start = std::chrono::steady_clock::now();
  const StatusOr<LaserLog> log = ParseLaserCsv(header + "\n" + kRow, "wide.csv");
  EXPECT_LT(SecondsSince(start), 2.0);
  ExpectMessage(StatusOf(log), {"wide.csv:1:", "200006 columns", "more than the 10000"});
}

TEST(ReaderLimitsTest, LineOfMillionsOfColumnsIsRefusedNamingItsLine) {
  // The style of a 150-million-column line, at a size a test can afford: 4 MB of commas.
  const std::string text = kHeader + kRow + std::string(4 << 20, ',') + "\n" + kRow;
  const auto start = std::chrono::steady_clock::now();
  const StatusOr<LaserLog> log = ParseLaserCsv(text, "commas.csv");
  EXPECT_LT(SecondsSince(start), 2.0);
  ExpectMessage(StatusOf(log), {"commas.csv:3:", "line longer than 1048576 bytes"});
}

TEST(ReaderLimitsTest, UnendedLastLineIsBoundedToo) {
  ExpectMessage(StatusOf(ParseLaserCsv(kHeader + std::string(2 << 20, '1'), "tail.csv")),
                {"tail.csv:2:", "line longer than"});
  // Just under the bound, the line is read (and found malformed, not too long).
  const Status short_enough =
      StatusOf(ParseLaserCsv(kHeader + std::string((1 << 20) - 10, '1') + "\n", "ok.csv"));
  ExpectMessage(short_enough, {"ok.csv:2:", "found 1 fields"});
}

TEST(ReaderLimitsTest, SparseTwoGigabyteFileIsRefusedAsNotTextWithoutReadingIt) {
  TempDir dir;
  const std::string path = dir / "sparse.csv";
  const int fd = open(path.c_str(), O_CREAT | O_WRONLY | O_TRUNC, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(ftruncate(fd, off_t{2} << 30), 0);
  close(fd);
  const long rss_before_kb = MaxRssKb();
  const auto start = std::chrono::steady_clock::now();
  const StatusOr<LaserLog> log = ReadLaserLog(path);
  EXPECT_LT(SecondsSince(start), 2.0);
  ExpectMessage(StatusOf(log), {path, "not a text file", "NUL byte at byte 0"});
  EXPECT_LT(MaxRssKb() - rss_before_kb, 64 * 1024) << "the file's size was allocated";
}

TEST(ReaderLimitsTest, NulByteInTheFirstBytesMarksABinaryFile) {
  TempDir dir;
  const std::string path = dir / "binary.csv";
  const std::string binary(
      "\x7f"
      "ELF\0\0",
      6);
  ASSERT_TRUE(WriteWholeFile(path, kHeader + kRow + binary + kRow).ok());
  ExpectMessage(StatusOf(ReadLaserLog(path)), {path, "not a text file", "NUL byte at byte"});
}

TEST(ReaderLimitsTest, EmptyFileAndPipeAreRead) {
  TempDir dir;
  const std::string empty = dir / "empty.csv";
  ASSERT_TRUE(WriteWholeFile(empty, "").ok());
  ExpectMessage(StatusOf(ReadLaserLog(empty, LaserFormat::kCsv)), {empty, "holds no records"});

  // A pipe cannot be mapped: it is read instead.
  const std::string fifo = dir / "log.csv";
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  std::thread writer([&] { EXPECT_TRUE(WriteWholeFile(fifo, kHeader + kRow + kRow).ok()); });
  const StatusOr<LaserLog> log = ReadLaserLog(fifo, LaserFormat::kCsv);
  writer.join();
  ASSERT_TRUE(log.ok()) << log.message();
  EXPECT_EQ(log->intervals.size(), 1u);  // The second row is an exact duplicate, dropped.
}

TEST(ReaderLimitsTest, MappedFileOwnsItsBytesAcrossMoves) {
  TempDir dir;
  const std::string path = dir / "a.txt";
  ASSERT_TRUE(WriteWholeFile(path, "hello\n").ok());
  StatusOr<MappedFile> opened = MappedFile::OpenText(path);
  ASSERT_TRUE(opened.ok()) << opened.message();
  MappedFile file = std::move(opened).value();
  MappedFile moved = std::move(file);
  EXPECT_EQ(moved.text(), "hello\n");
  EXPECT_EQ(file.text(), "");
  ExpectMessage(StatusOf(MappedFile::Open(dir / "missing")), {"missing: no such file"});
  // A file whose size says 0 but that holds bytes is read, not mapped.
  const StatusOr<MappedFile> proc = MappedFile::OpenText("/proc/self/status");
  ASSERT_TRUE(proc.ok()) << proc.message();
  EXPECT_NE(proc->text().find("Name:"), std::string_view::npos);
  ExpectMessage(StatusOf(MappedFile::Open(dir / ".")), {"is a directory"});
}

// Resident file pages of this process, kB (RssFile in /proc/self/status; -1: unknown).
long ResidentFileKb() {
  const StatusOr<MappedFile> status = MappedFile::OpenText("/proc/self/status");
  if (!status.ok()) return -1;
  const size_t at = status->text().find("RssFile:");
  return at == std::string_view::npos ? -1 : std::atol(status->text().data() + at + 8);
}

// A long log's parse keeps a window of its mapped file resident, not all of it, and reads the
// same intervals as a parse that keeps everything.
TEST(ReaderLimitsTest, ParsedBytesOfAMappedFileAreReleased) {
  TempDir dir;
  const std::string path = dir / "long.tuple";
  std::string text;
  for (int k = 0; k < 600000; ++k) {  // About 60 MB, more than three release windows.
    text += "{\"T\": 0.5, \"phi_l\": " + std::to_string(1.0 + 1e-6 * k) +
            ", \"phi_r\": 1.2, \"sm\": [0.05, 0.001, 0.01]}\n";
  }
  ASSERT_TRUE(WriteWholeFile(path, text).ok());
  StatusOr<MappedFile> file = MappedFile::OpenText(path);
  ASSERT_TRUE(file.ok()) << file.message();
  std::vector<const char*> released;
  long most_resident_kb = 0;
  std::mutex mutex;  // A long text's two halves release at once.
  const ReleaseText release = [&](const char* begin, const char* end) {
    file->Release(begin, end);
    const long resident_kb = ResidentFileKb();
    const std::lock_guard<std::mutex> lock(mutex);
    released.push_back(begin);
    most_resident_kb = std::max(most_resident_kb, resident_kb);
  };
  const StatusOr<LaserLog> windowed = ParseLaserTuples(file->text(), path, release);
  const StatusOr<LaserLog> whole = ParseLaserTuples(text, path);
  ASSERT_TRUE(windowed.ok() && whole.ok()) << windowed.message();
  ASSERT_EQ(windowed->intervals.size(), 600000u);
  ASSERT_EQ(windowed->intervals.size(), whole->intervals.size());
  for (size_t k = 0; k < whole->intervals.size(); k += 997) {
    EXPECT_EQ(windowed->intervals[k].left_speed, whole->intervals[k].left_speed);
    EXPECT_EQ(windowed->intervals[k].line, whole->intervals[k].line);
  }
  EXPECT_GE(released.size(), 3u);  // One pass, past three windows.
  if (most_resident_kb >= 0) {
    // The text's own copy is in anonymous memory; the mapped file keeps at most a window or two.
    EXPECT_LT(most_resident_kb, static_cast<long>(2 * kReleaseTextBytes / 1024))
        << most_resident_kb << " kB of file pages resident";
  }
  // Dropped pages read back from the file.
  EXPECT_EQ(file->text().substr(0, 64), std::string_view(text).substr(0, 64));
}

TEST(ReaderLimitsTest, TupleRecordIsBoundedNotTheLine) {
  const std::string record = R"({"T":0.5,"phi_l":1,"phi_r":1.2,"sm":[0.05,0.001,0.01]} )";
  // Ten thousand records on one line (> 1 MiB together) are read: the bound is per record.
  std::string line;
  for (int i = 0; i < 20000; ++i) {
    line += R"({"T":0.5,"phi_l":1,"phi_r":)" + std::to_string(1.0 + 1e-4 * i) +
            R"(,"sm":[0.05,0.001,0.01]} )";
  }
  ASSERT_GT(line.size(), size_t{1} << 20);
  const StatusOr<LaserLog> many = ParseLaserTuples(line + "\n", "one_line.tuple");
  ASSERT_TRUE(many.ok()) << many.message();
  EXPECT_EQ(many->intervals.size(), 20000u);
  // One record of 2 MB (white space inside it) is refused, naming it.
  const std::string huge = record + "\n" + R"({"T":0.5,"phi_l":1,)" + std::string(2 << 20, ' ');
  ExpectMessage(StatusOf(ParseLaserTuples(huge, "huge.tuple")),
                {"huge.tuple:2:", "record 2", "longer than 1048576 bytes"});
  // An sm array of a million numbers stops at the bound too.
  std::string sm = R"({"T":0.5,"phi_l":1,"phi_r":1,"sm":[)";
  for (int i = 0; i < 600000; ++i) sm += "1,";
  ExpectMessage(StatusOf(ParseLaserTuples(sm, "sm.tuple")), {"sm.tuple:1:", "longer than"});
}

TEST(ReaderLimitsTest, FileOfBracesDoesNotReserveARecordPerBrace) {
  const StatusOr<LaserLog> log = ParseLaserTuples(std::string(8 << 20, '{'), "braces.tuple");
  ExpectMessage(StatusOf(log), {"braces.tuple:1:", "record 1"});
}

TEST(ReaderLimitsTest, LineCountersCannotOverflow) {
  // A file of more than 2^31 lines cannot be made in a test: the counters are 64-bit, and the
  // int fields of a log saturate instead of wrapping.
  StatusOr<CsvReader> csv = CsvReader::Open("a\n1\n", "c.csv", {{"a"}});
  ASSERT_TRUE(csv.ok());
  static_assert(std::is_same_v<decltype(csv->line()), int64_t>);
  static_assert(std::is_same_v<decltype(csv->record()), int64_t>);
  static_assert(std::is_same_v<decltype(csv->header_line()), int64_t>);
  EXPECT_EQ(SaturatedInt(int64_t{3} << 31), INT_MAX);
  EXPECT_EQ(SaturatedInt(12345), 12345);
  // Lines past the first few are still counted exactly (a tuple after 100000 blank lines).
  const std::string tuple = R"({"T":0.5,"phi_l":1,"phi_r":1.2,"sm":[0.05,0.001,0.01]})";
  ExpectMessage(StatusOf(ParseLaserTuples(std::string(100000, '\n') + tuple + " x", "n.tuple")),
                {"n.tuple:100001:", "unexpected text 'x'"});
}

TEST(ReaderLimitsTest, HourLongStreamsAreAnalysedWithoutOverflow) {
  // 320000 samples at 100 Hz (53 min): the grid fit's block bounds once overflowed an int here.
  std::vector<double> stamps(320000);
  for (size_t k = 0; k < stamps.size(); ++k) stamps[k] = 0.01 * static_cast<double>(k);
  const StreamTiming timing = AnalyzeStreamTiming(stamps, {}, "odometry", "long.csv");
  EXPECT_EQ(timing.samples, 320000);
  EXPECT_NEAR(timing.period_s, 0.01, 1e-9);
  EXPECT_EQ(timing.gaps, 0);
}

TEST(ReaderLimitsTest, AllocationFailureBecomesAnErrorNamingTheFile) {
  const Status status = GuardAllocation("big.csv", []() -> Status { throw std::bad_alloc(); });
  ExpectMessage(status, {"big.csv", "out of memory"});
  EXPECT_EQ(status.code(), StatusCode::kIo);
  const StatusOr<int> length =
      GuardAllocation("long.csv", []() -> StatusOr<int> { throw std::length_error("vector"); });
  ExpectMessage(StatusOf(length), {"long.csv", "out of memory"});
}

TEST(ReaderLimitsTest, BearingMetaOfMegabytesIsRefused) {
  const std::string odometry = "run,t,left,right\n1,0,0,0\n1,1,1,1\n";
  const std::string bearings = "run,t,bearing\n1,0.5,0.1\n";
  const std::string meta = R"({"wheel_radius": 0.3, "wheelbase": 0.5})";
  EXPECT_TRUE(ParseBearingLog(odometry, bearings, meta, "dir").ok());
  ExpectMessage(
      StatusOf(ParseBearingLog(odometry, bearings, meta + std::string(2 << 20, ' '), "dir")),
      {"meta.json", "bytes, more than"});
}

std::string Bytes(const std::string& path) {
  std::string bytes;
  EXPECT_TRUE(ReadWholeFile(path, &bytes).ok()) << path;
  return bytes;
}

const std::string kBags = std::string(CALIB_SOURCE_DIR) + "/data/bags/";

TEST(ReaderLimitsTest, Ros1LengthFieldOfFourGigabytesIsRefusedNamingTheRecord) {
  std::string bag = Bytes(kBags + "small_robot_none.bag");
  ASSERT_TRUE(ReadRos1BagBytes(bag, "small.bag").ok());
  const size_t first_record = 13;  // After "#ROSBAG V2.0\n".
  std::memset(&bag[first_record], 0xFF, 4);
  const auto start = std::chrono::steady_clock::now();
  ExpectMessage(StatusOf(ReadRos1BagBytes(bag, "huge.bag")),
                {"huge.bag", "record at byte 13", "truncated", "runs past the end"});
  EXPECT_LT(SecondsSince(start), 1.0);
}

TEST(ReaderLimitsTest, McapLengthFieldBeyondTheFileIsRefusedNamingTheRecord) {
  std::string bag = Bytes(kBags + "small_robot_nosummary.mcap");
  ASSERT_TRUE(ReadMcapBytes(bag, "small.mcap").ok());
  const size_t header_record = 8;  // After the magic: opcode, then the u64 length.
  std::memset(&bag[header_record + 1], 0xFF, 8);
  ExpectMessage(StatusOf(ReadMcapBytes(bag, "huge.mcap")),
                {"huge.mcap", "at byte 8", "runs past the end"});
}

// The format sniffers read a file's head, never more than asked, and nothing from what is not a
// readable file.
TEST(ReaderLimitsTest, FileHeadIsAtMostWhatIsAsked) {
  TempDir dir;
  const std::string path = dir / "head.txt";
  std::string text;
  for (int i = 0; i < 100; ++i) text += static_cast<char>('a' + i % 26);
  ASSERT_TRUE(WriteWholeFile(path, text).ok());
  EXPECT_EQ(ReadFileHead(path, 16), text.substr(0, 16));
  EXPECT_EQ(ReadFileHead(path, 1000), text);
  EXPECT_EQ(ReadFileHead(path, 0), "");
  EXPECT_EQ(ReadFileHead(dir / "missing.txt", 16), "");
  EXPECT_EQ(ReadFileHead(dir / ".", 16), "");  // A directory.
}

}  // namespace
}  // namespace calib
