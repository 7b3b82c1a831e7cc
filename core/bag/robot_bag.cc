#include <calib/core/bag/robot_bag.h>
#include <calib/core/text_file.h>

#include <filesystem>

namespace calib {
namespace {

namespace fs = std::filesystem;

constexpr char kMcapMagic[] = "\x89MCAP0\r\n";
constexpr char kRos1Magic[] = "#ROSBAG V";
constexpr char kOldRos1Magic[] = "#ROSRECORD V";  // Bags of format 1.x (before ROS 1.1).
constexpr char kSqliteMagic[] = "SQLite format 3";

bool StartsWith(const std::string& bytes, const char* magic) {
  return bytes.compare(0, std::char_traits<char>::length(magic), magic) == 0;
}

// A ROS 1 bag of any version (the reader names the versions it does not read).
bool Ros1Bag(const std::string& bytes) {
  return StartsWith(bytes, kRos1Magic) || StartsWith(bytes, kOldRos1Magic);
}

bool BagDirectory(const std::string& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return false;
  if (fs::exists(fs::path(path) / "metadata.yaml", ec)) return true;
  for (const fs::directory_entry& e : fs::directory_iterator(path, ec)) {
    if (e.path().extension() == ".mcap") return true;
  }
  return HoldsSqliteBag(path);
}

bool SqliteBagName(const std::string& path) {
  const std::string name = fs::path(path).filename().string();
  const auto ends = [&](const std::string& suffix) {
    return name.size() > suffix.size() &&
           name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  return ends(".db3") || ends(".db3.zstd");
}

}  // namespace

bool LooksLikeRobotBag(const std::string& path) {
  if (BagDirectory(path)) return true;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return false;
  const std::string extension = fs::path(path).extension().string();
  // Read as one, or said not to be.
  if (extension == ".mcap" || extension == ".bag" || SqliteBagName(path)) return true;
  const std::string bytes = ReadFileHead(path, 16);
  return StartsWith(bytes, kMcapMagic) || Ros1Bag(bytes) || StartsWith(bytes, kSqliteMagic);
}

StatusOr<RobotMessages> ReadRobotBag(const std::string& path, const BagReadOptions& options) {
  if (BagDirectory(path)) {
    return HoldsSqliteBag(path) ? ReadSqliteBag(path, options) : ReadMcapBag(path, options);
  }
  std::error_code ec;
  if (!fs::exists(path, ec)) return Status::Io(path + ": no such file or directory");
  const std::string bytes = ReadFileHead(path, 16);
  if (Ros1Bag(bytes)) return ReadRos1Bag(path, options);
  if (StartsWith(bytes, kMcapMagic)) return ReadMcapBag(path, options);
  if (StartsWith(bytes, kSqliteMagic) || (SqliteBagName(path) && !bytes.empty())) {
    return ReadSqliteBag(path, options);
  }
  return Status::InvalidInput(path + ": not a bag: " +
                              (bytes.empty() ? std::string("the file is empty")
                                             : "it starts with neither MCAP's, ROS 1's nor "
                                               "SQLite's magic"));
}

}  // namespace calib
