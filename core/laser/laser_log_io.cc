#include <calib/core/laser/laser_log_builder.h>
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_plausibility.h>
#include <calib/core/text_file.h>
#include <calib/core/text_number.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace calib {
namespace fs = std::filesystem;

StatusOr<LaserFormat> ParseLaserFormat(const std::string& name) {
  std::string lower = name;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower == "auto") return LaserFormat::kAuto;
  if (lower == "tuples" || lower == "json") return LaserFormat::kTuples;
  if (lower == "csv") return LaserFormat::kCsv;
  if (lower == "stream") return LaserFormat::kStream;
  return Status::InvalidInput("unknown laser log format '" + name +
                              "'; accepted: auto, tuples, json, csv, stream");
}

StatusOr<LaserLog> ReadLaserLog(const std::string& path, LaserFormat format) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) return Status::Io(path + ": no such file or directory");
  const bool directory = fs::is_directory(status);
  if (format == LaserFormat::kStream || (format == LaserFormat::kAuto && directory)) {
    if (!directory) {
      return Status::InvalidInput(path +
                                  ": the stream format reads a directory holding odometry.csv "
                                  "and sensor_poses.csv, but this is a file");
    }
    return ReadLaserStream(path);
  }
  CALIB_ASSIGN_OR_RETURN(const MappedFile file, MappedFile::OpenText(path));
  return ParseLaserLog(file.text(), path, format, file.Releaser());
}

StatusOr<LaserLog> ParseLaserLog(std::string_view text, const std::string& source,
                                 LaserFormat format, const ReleaseText& release) {
  if (format == LaserFormat::kStream) {
    return Status::InvalidInput(source + ": the stream format is a directory, not one file's text");
  }
  if (format == LaserFormat::kAuto) {
    const std::string_view body = WithoutBom(text);
    size_t i = 0;
    while (i < body.size() && laser_io_internal::IsJsonSpace(body[i])) ++i;
    format = i < body.size() && body[i] == '{' ? LaserFormat::kTuples : LaserFormat::kCsv;
  }
  CALIB_ASSIGN_OR_RETURN(LaserLog log, format == LaserFormat::kTuples
                                           ? ParseLaserTuples(text, source, release)
                                           : ParseLaserCsv(text, source, release));
  return GuardAllocation(source, [&]() -> StatusOr<LaserLog> {
    const size_t read = log.intervals.size();
    DropImplausibleIntervals(&log);
    if (log.intervals.empty()) {
      return Status::InvalidInput(source + ": every one of its " + std::to_string(read) +
                                  " record(s) is implausible: " + log.warnings.back());
    }
    return std::move(log);
  });
}

}  // namespace calib
