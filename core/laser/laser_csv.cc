#include <calib/core/csv.h>
#include <calib/core/laser/laser_log_builder.h>
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/text_file.h>
#include <calib/core/text_number.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <string_view>
#include <utility>

namespace calib {

using laser_io_internal::CheckWritable;
using laser_io_internal::LogBuilder;

// The CSV format: a header naming T,phi_l,phi_r,sm_x,sm_y,sm_theta and optionally t.
namespace {

StatusOr<LaserLog> ParseCsv(std::string_view text, const std::string& source,
                            const ReleaseText& release) {
  enum { kT, kPhiL, kPhiR, kSmX, kSmY, kSmTheta, kStart };
  CALIB_ASSIGN_OR_RETURN(CsvReader csv, CsvReader::Open(text, source,
                                                        {{"T"},
                                                         {"phi_l"},
                                                         {"phi_r"},
                                                         {"sm_x"},
                                                         {"sm_y"},
                                                         {"sm_theta"},
                                                         {"t", /*required=*/false}}));
  LogBuilder builder(source);
  // A reserve saves regrowing a large vector; a file of newlines must not reserve more
  // records than its bytes can hold ("1,1,1,1,1,1" and its newline).
  constexpr size_t kMinRecordBytes = 12;
  builder.Reserve(std::min(EstimateByteCount(text, '\n'), text.size() / kMinRecordBytes));
  size_t released = 0;
  while (true) {
    CALIB_ASSIGN_OR_RETURN(const bool more, csv.Next());
    if (!more) break;
    double v[kStart + 1] = {};
    for (int c = kT; c < kStart; ++c) CALIB_RETURN_IF_ERROR(csv.Number(c, &v[c]));
    bool has_t = false;
    CALIB_RETURN_IF_ERROR(csv.Number(kStart, &v[kStart], &has_t));
    LaserInterval interval;
    interval.duration_s = v[kT];
    interval.left_speed = v[kPhiL];
    interval.right_speed = v[kPhiR];
    interval.sensor_motion = Pose2d(v[kSmX], v[kSmY], v[kSmTheta]);
    interval.start_s = v[kStart];
    interval.line = SaturatedInt(csv.line());
    interval.record = SaturatedInt(csv.record());
    CALIB_RETURN_IF_ERROR(builder.Add(std::move(interval), has_t));
    const size_t read = static_cast<size_t>(csv.position() - text.data());
    if (release && read >= released + kReleaseTextBytes) {
      release(text.data() + released, csv.position());
      released = read;
    }
  }
  return std::move(builder).Finish(" (only a header)");
}

}  // namespace

StatusOr<LaserLog> ParseLaserCsv(std::string_view text, const std::string& source,
                                 const ReleaseText& release) {
  return GuardAllocation(source, [&] { return ParseCsv(text, source, release); });
}

Status WriteLaserCsv(const LaserLog& log, const std::string& path) {
  CALIB_RETURN_IF_ERROR(CheckWritable(log, path));
  std::string out = "t,T,phi_l,phi_r,sm_x,sm_y,sm_theta\n";
  out.reserve(log.intervals.size() * 120 + out.size());
  for (const LaserInterval& interval : log.intervals) {
    const double values[7] = {interval.start_s,          interval.duration_s,
                              interval.left_speed,       interval.right_speed,
                              interval.sensor_motion(0), interval.sensor_motion(1),
                              interval.sensor_motion(2)};
    for (int i = 0; i < 7; ++i) {
      if (i > 0) out += ',';
      AppendGeneral(&out, values[i]);
    }
    out += '\n';
  }
  return WriteWholeFile(path, out);
}

}  // namespace calib
