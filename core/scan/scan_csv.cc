#include <calib/core/csv.h>
#include <calib/core/scan/scan_csv.h>
#include <calib/core/text_file.h>
#include <calib/core/text_number.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <map>
#include <string_view>
#include <system_error>
#include <utility>

namespace calib {
namespace {

constexpr float kNoReturn = std::numeric_limits<float>::quiet_NaN();
// A long-layout scan's angles may differ from an even grid by this much (rad).
constexpr double kAngleTolerance = 1e-9;

std::string Lower(std::string_view s) {
  std::string lower(s);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return lower;
}

// A range cell: empty or nan is no return (NaN), ±inf kept; otherwise a float read exactly as
// std::from_chars<float> does, so the writer's shortest float text reads back bit for bit.
Status ParseRange(const CsvReader& csv, size_t column, const char* name, float* range) {
  const std::string_view field = csv.Field(column);
  const std::string lower = Lower(field);
  if (lower.empty() || lower == "nan" || lower == "-nan" || lower == "+nan") {
    *range = kNoReturn;
    return Status::Ok();
  }
  if (lower == "inf" || lower == "+inf" || lower == "infinity" || lower == "+infinity") {
    *range = std::numeric_limits<float>::infinity();
    return Status::Ok();
  }
  if (lower == "-inf" || lower == "-infinity") {
    *range = -std::numeric_limits<float>::infinity();
    return Status::Ok();
  }
  const char* begin = field.data() + (field.front() == '+' ? 1 : 0);
  const auto [end, error] = std::from_chars(begin, field.data() + field.size(), *range);
  if (error == std::errc() && end == field.data() + field.size() && std::isfinite(*range)) {
    return Status::Ok();
  }
  return Status::InvalidInput(csv.Where() + name + " is not a number: '" + std::string(field) +
                              "'");
}

// t may repeat only in a record written twice (the reader of the scans drops it with a warning).
Status CheckIncreasing(const CsvReader& csv, const std::vector<LaserScan>& scans, double t) {
  if (scans.empty() || t >= scans.back().stamp_s) return Status::Ok();
  return Status::InvalidInput(
      csv.Where() + "t = " + Num(t) + " does not increase (the scan before, line " +
      std::to_string(scans.back().record) + ", has t = " + Num(scans.back().stamp_s) + ")");
}

bool SameRecord(const LaserScan& a, const LaserScan& b) {
  const auto same = [](double x, double y) { return x == y || (std::isnan(x) && std::isnan(y)); };
  return a.stamp_s == b.stamp_s && a.angle_min_rad == b.angle_min_rad &&
         a.angle_increment_rad == b.angle_increment_rad &&
         a.time_increment_s == b.time_increment_s && same(a.range_min_m, b.range_min_m) &&
         same(a.range_max_m, b.range_max_m) && a.ranges_m.size() == b.ranges_m.size() &&
         std::memcmp(a.ranges_m.data(), b.ranges_m.data(), a.ranges_m.size() * sizeof(float)) == 0;
}

// The last scan read, when its t repeats the one before, must repeat all of it.
Status CheckRepeat(const std::string& source, const std::vector<LaserScan>& scans) {
  const size_t n = scans.size();
  if (n < 2 || scans[n - 1].stamp_s != scans[n - 2].stamp_s ||
      SameRecord(scans[n - 1], scans[n - 2])) {
    return Status::Ok();
  }
  return Status::InvalidInput(
      source + ":" + std::to_string(scans[n - 1].record) + ": t = " + Num(scans[n - 1].stamp_s) +
      " repeats the scan before (line " + std::to_string(scans[n - 2].record) +
      ") with other values (a record written twice would repeat them)");
}

// The optional per-scan columns time_increment, range_min, range_max (defaults 0, 0, +inf).
Status ReadOptional(const CsvReader& csv, size_t first, LaserScan* scan) {
  double* values[3] = {&scan->time_increment_s, &scan->range_min_m, &scan->range_max_m};
  scan->range_max_m = std::numeric_limits<double>::infinity();
  for (size_t c = 0; c < 3; ++c) CALIB_RETURN_IF_ERROR(csv.Number(first + c, values[c]));
  return Status::Ok();
}

LaserScan NewScan(const CsvReader& csv, double t) {
  LaserScan scan;
  scan.stamp_s = scan.log_time_s = t;
  scan.record = csv.line();
  return scan;
}

StatusOr<std::vector<LaserScan>> ParseWide(std::string_view text, const std::string& source,
                                           const std::vector<std::string>& names) {
  // Which range_<k> the header names; every k below the largest must be there.
  std::map<size_t, bool> indices;
  for (const std::string& name : names) {
    const std::string lower = Lower(name);
    if (lower.rfind("range_", 0) != 0 || lower.size() == 6 || lower.size() > 15) continue;
    if (!std::all_of(lower.begin() + 6, lower.end(), [](char c) { return std::isdigit(c); })) {
      continue;
    }
    indices[std::stoul(lower.substr(6))] = true;
  }
  const size_t n = indices.empty() ? 0 : indices.rbegin()->first + 1;
  for (size_t k = 0; k < n; ++k) {
    if (indices.count(k) == 0) {
      return Status::InvalidInput(source + ": the header lacks the column range_" +
                                  std::to_string(k) + " (it names range_" + std::to_string(n - 1) +
                                  ")");
    }
  }
  std::vector<std::string> range_names;
  for (size_t k = 0; k < n; ++k) range_names.push_back("range_" + std::to_string(k));
  enum { kT, kAngleMin, kIncrement, kTimeIncrement, kRangeMin, kRangeMax, kFirstRange };
  std::vector<CsvColumn> columns = {{"t"},
                                    {"angle_min"},
                                    {"angle_increment"},
                                    {"time_increment", false},
                                    {"range_min", false},
                                    {"range_max", false}};
  for (const std::string& name : range_names) columns.push_back({name.c_str()});
  CALIB_ASSIGN_OR_RETURN(CsvReader csv, CsvReader::Open(text, source, std::move(columns)));
  if (n == 0) {
    return Status::InvalidInput(source + ":" + std::to_string(csv.header_line()) +
                                ": the header names no range_0, range_1, ... columns");
  }
  std::vector<LaserScan> scans;
  while (true) {
    CALIB_ASSIGN_OR_RETURN(const bool more, csv.Next());
    if (!more) break;
    double t = 0.0;
    CALIB_RETURN_IF_ERROR(csv.Number(kT, &t));
    CALIB_RETURN_IF_ERROR(CheckIncreasing(csv, scans, t));
    LaserScan scan = NewScan(csv, t);
    CALIB_RETURN_IF_ERROR(csv.Number(kAngleMin, &scan.angle_min_rad));
    CALIB_RETURN_IF_ERROR(csv.Number(kIncrement, &scan.angle_increment_rad));
    CALIB_RETURN_IF_ERROR(ReadOptional(csv, kTimeIncrement, &scan));
    scan.ranges_m.resize(n);
    for (size_t k = 0; k < n; ++k) {
      CALIB_RETURN_IF_ERROR(
          ParseRange(csv, kFirstRange + k, range_names[k].c_str(), &scan.ranges_m[k]));
    }
    scans.push_back(std::move(scan));
    CALIB_RETURN_IF_ERROR(CheckRepeat(source, scans));
  }
  return scans;
}

// Fixes a finished long-layout scan's angle grid from its beams' angles.
Status FinishLongScan(const std::string& source, const std::vector<double>& angles,
                      LaserScan* scan) {
  const size_t n = angles.size();
  scan->angle_min_rad = angles.front();
  scan->angle_increment_rad = n > 1 ? (angles.back() - angles.front()) / (n - 1) : 0.0;
  for (size_t i = 0; i < n; ++i) {
    if (std::abs(angles[i] - scan->BeamAngle(static_cast<int>(i))) > kAngleTolerance) {
      return Status::InvalidInput(source + ":" + std::to_string(scan->record + i) +
                                  ": the scan at t = " + Num(scan->stamp_s) + " (from line " +
                                  std::to_string(scan->record) + "): beam " + std::to_string(i) +
                                  "'s angle " + Num(angles[i]) + " is off the scan's even grid");
    }
  }
  return Status::Ok();
}

StatusOr<std::vector<LaserScan>> ParseLong(std::string_view text, const std::string& source) {
  enum { kT, kAngle, kRange, kTimeIncrement, kRangeMin, kRangeMax };
  CALIB_ASSIGN_OR_RETURN(CsvReader csv, CsvReader::Open(text, source,
                                                        {{"t"},
                                                         {"angle"},
                                                         {"range"},
                                                         {"time_increment", false},
                                                         {"range_min", false},
                                                         {"range_max", false}}));
  std::vector<LaserScan> scans;
  std::vector<double> angles;
  while (true) {
    CALIB_ASSIGN_OR_RETURN(const bool more, csv.Next());
    if (!more) break;
    double t = 0.0, angle = 0.0;
    float range = 0.0f;
    CALIB_RETURN_IF_ERROR(csv.Number(kT, &t));
    CALIB_RETURN_IF_ERROR(csv.Number(kAngle, &angle));
    CALIB_RETURN_IF_ERROR(ParseRange(csv, kRange, "range", &range));
    // A scan's rows share t; its first angle again under the same t starts the scan written twice.
    const bool again = !scans.empty() && t == scans.back().stamp_s && angle == angles.front();
    if (scans.empty() || t != scans.back().stamp_s || again) {
      CALIB_RETURN_IF_ERROR(CheckIncreasing(csv, scans, t));
      if (!scans.empty()) {
        CALIB_RETURN_IF_ERROR(FinishLongScan(source, angles, &scans.back()));
        CALIB_RETURN_IF_ERROR(CheckRepeat(source, scans));
      }
      scans.push_back(NewScan(csv, t));
      CALIB_RETURN_IF_ERROR(ReadOptional(csv, kTimeIncrement, &scans.back()));
      angles.clear();
    }
    angles.push_back(angle);
    scans.back().ranges_m.push_back(range);
  }
  if (!scans.empty()) {
    CALIB_RETURN_IF_ERROR(FinishLongScan(source, angles, &scans.back()));
    CALIB_RETURN_IF_ERROR(CheckRepeat(source, scans));
  }
  return scans;
}

void AppendRange(std::string* out, float range) {
  if (std::isnan(range)) {
    *out += "nan";
  } else if (std::isinf(range)) {
    *out += range > 0 ? "inf" : "-inf";
  } else {
    char buffer[32];
    const auto result = std::to_chars(buffer, buffer + sizeof(buffer), range);
    out->append(buffer, result.ptr);
  }
}

void AppendValues(std::string* out, std::initializer_list<double> values) {
  for (const double v : values) {
    AppendGeneral(out, v);
    *out += ',';
  }
}

// range_min/range_max: an empty cell (the reader's default) when not finite.
void AppendLimit(std::string* out, double value) {
  if (std::isfinite(value)) AppendGeneral(out, value);
}

StatusOr<std::vector<LaserScan>> ParseScan(std::string_view text, const std::string& source) {
  // The header alone tells the layout: a column "angle" means long.
  CALIB_ASSIGN_OR_RETURN(CsvReader header, CsvReader::Open(text, source, {}));
  (void)header;
  const std::string_view body = WithoutBom(text);
  std::vector<std::string> names;
  size_t pos = 0;
  while (pos < body.size()) {  // The first line neither blank nor a comment.
    const size_t stop = std::min(body.find('\n', pos), body.size());
    std::string_view line = body.substr(pos, stop - pos);
    pos = stop + 1;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string_view::npos || line[first] == '#') continue;
    size_t start = 0;
    while (start <= line.size()) {
      const size_t comma = std::min(line.find(',', start), line.size());
      std::string_view name = line.substr(start, comma - start);
      const size_t a = name.find_first_not_of(" \t\r\""), b = name.find_last_not_of(" \t\r\"");
      names.emplace_back(a == std::string_view::npos ? "" : name.substr(a, b - a + 1));
      start = comma + 1;
    }
    break;
  }
  const bool is_long = std::any_of(names.begin(), names.end(),
                                   [](const std::string& n) { return Lower(n) == "angle"; });
  return is_long ? ParseLong(text, source) : ParseWide(text, source, names);
}

}  // namespace

StatusOr<std::vector<LaserScan>> ParseScanCsv(std::string_view text, const std::string& source) {
  return GuardAllocation(source, [&] { return ParseScan(text, source); });
}

StatusOr<std::vector<LaserScan>> ReadScanCsv(const std::string& path) {
  CALIB_ASSIGN_OR_RETURN(const MappedFile file, MappedFile::OpenText(path));
  return ParseScanCsv(file.text(), path);
}

std::string FormatScanCsv(const std::vector<LaserScan>& scans, ScanCsvLayout layout) {
  std::string out;
  if (layout == ScanCsvLayout::kLong) {
    out = "t,angle,range,time_increment,range_min,range_max\n";
    for (const LaserScan& scan : scans) {
      for (int i = 0; i < static_cast<int>(scan.ranges_m.size()); ++i) {
        AppendValues(&out, {scan.stamp_s, scan.BeamAngle(i)});
        AppendRange(&out, scan.ranges_m[i]);
        out += ',';
        AppendValues(&out, {scan.time_increment_s});
        AppendLimit(&out, scan.range_min_m);
        out += ',';
        AppendLimit(&out, scan.range_max_m);
        out += '\n';
      }
    }
    return out;
  }
  size_t n = 0;
  for (const LaserScan& scan : scans) n = std::max(n, scan.ranges_m.size());
  out = "t,angle_min,angle_increment,time_increment,range_min,range_max";
  for (size_t k = 0; k < n; ++k) out += ",range_" + std::to_string(k);
  out += '\n';
  for (const LaserScan& scan : scans) {
    AppendValues(
        &out, {scan.stamp_s, scan.angle_min_rad, scan.angle_increment_rad, scan.time_increment_s});
    AppendLimit(&out, scan.range_min_m);
    out += ',';
    AppendLimit(&out, scan.range_max_m);
    // A shorter scan's missing beams are written as no return.
    for (size_t k = 0; k < n; ++k) {
      out += ',';
      AppendRange(&out, k < scan.ranges_m.size() ? scan.ranges_m[k] : kNoReturn);
    }
    out += '\n';
  }
  return out;
}

Status WriteScanCsv(const std::vector<LaserScan>& scans, ScanCsvLayout layout,
                    const std::string& path) {
  return WriteWholeFile(path, FormatScanCsv(scans, layout));
}

}  // namespace calib
