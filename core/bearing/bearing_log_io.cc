#include <calib/core/bearing/bearing_log_io.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string_view>
#include <system_error>
#include <utility>

#include <calib/core/text_file.h>

namespace calib {
namespace {

namespace fs = std::filesystem;

// A bearing this far beyond ±π is still taken as wrapped (rounding in the writer's own output).
constexpr double kBearingSlack = 1e-9;

std::string Num(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  return std::string(buffer, result.ptr);
}

std::string At(const std::string& source, int line) {
  return line > 0 ? source + ":" + std::to_string(line) + ": " : source + ": ";
}

std::string_view Trim(std::string_view s) {
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  return s;
}

std::string_view WithoutBom(std::string_view text) {
  if (text.size() >= 3 && text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.remove_prefix(3);
  return text;
}

// A CSV table: the header's column names, then rows of fields with their line numbers.
struct CsvRow {
  int line = 0;
  std::vector<std::string_view> fields;
};

struct CsvTable {
  int header_line = 0;
  std::vector<std::string> columns;
  std::vector<CsvRow> rows;
};

std::vector<std::string_view> SplitFields(std::string_view line) {
  std::vector<std::string_view> fields;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    fields.push_back(Trim(line.substr(start, comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

// Splits `text` into a header and rows, checking that every row has as many fields as the header
// and that the header names `required` (case-insensitive; other columns are ignored). On success
// `index[i]` is the column of required[i].
Status ReadCsv(std::string_view text, const std::string& source,
               const std::vector<std::string>& required, CsvTable* table,
               std::vector<size_t>* index) {
  text = WithoutBom(text);
  int line_number = 0;
  size_t start = 0;
  bool have_header = false;
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = Trim(text.substr(start, end - start));
    ++line_number;
    start = end + 1;
    if (line.empty() || line.front() == '#') continue;
    if (!have_header) {
      have_header = true;
      table->header_line = line_number;
      for (std::string_view name : SplitFields(line)) {
        std::string lower(name);
        for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
        table->columns.push_back(lower);
      }
      continue;
    }
    CsvRow row;
    row.line = line_number;
    row.fields = SplitFields(line);
    if (row.fields.size() != table->columns.size()) {
      return Status::Error(At(source, line_number) + "expected " +
                           std::to_string(table->columns.size()) + " comma-separated fields (as " +
                           "in the header), found " + std::to_string(row.fields.size()));
    }
    table->rows.push_back(std::move(row));
  }
  std::string wanted;
  for (const std::string& name : required) wanted += (wanted.empty() ? "" : ",") + name;
  if (!have_header) {
    return Status::Error(source + ": empty file, expected a header line '" + wanted + "'");
  }
  index->clear();
  for (const std::string& name : required) {
    const auto first = std::find(table->columns.begin(), table->columns.end(), name);
    if (first == table->columns.end()) {
      return Status::Error(At(source, table->header_line) + "the header has no column '" + name +
                           "' (expected " + wanted + ")");
    }
    if (std::find(first + 1, table->columns.end(), name) != table->columns.end()) {
      return Status::Error(At(source, table->header_line) + "column '" + name +
                           "' appears twice in the header");
    }
    index->push_back(static_cast<size_t>(first - table->columns.begin()));
  }
  if (table->rows.empty()) {
    return Status::Error(source + ": no samples after the header (line " +
                         std::to_string(table->header_line) + ")");
  }
  return Status::Ok();
}

// A finite double filling the whole field.
Status ParseDouble(std::string_view field, const std::string& name, const std::string& where,
                   double* value) {
  if (field.empty()) return Status::Error(where + "field '" + name + "' is empty");
  const char* end = field.data() + field.size();
  const char* begin = field.data();
  if (*begin == '+') ++begin;  // from_chars rejects a leading '+'.
  const auto result = std::from_chars(begin, end, *value);
  if (result.ec == std::errc::result_out_of_range) {
    *value = std::strtod(std::string(field).c_str(), nullptr);
  } else if (result.ec != std::errc() || result.ptr != end) {
    return Status::Error(where + "field '" + name + "' is not a number: '" + std::string(field) +
                         "'");
  }
  if (!std::isfinite(*value)) {
    return Status::Error(where + "field '" + name + "' must be finite, got '" + std::string(field) +
                         "'");
  }
  return Status::Ok();
}

Status ParseRunId(std::string_view field, const std::string& where, int* run) {
  if (field.empty()) return Status::Error(where + "field 'run' is empty");
  const char* end = field.data() + field.size();
  const auto result = std::from_chars(field.data(), end, *run);
  if (result.ec != std::errc() || result.ptr != end) {
    return Status::Error(where + "field 'run' must be an integer run id, got '" +
                         std::string(field) + "'");
  }
  return Status::Ok();
}

// The 1-based line of the first occurrence of `needle` in `text` (0 if absent).
int LineOf(const std::string& text, const std::string& needle) {
  const size_t at = text.find(needle);
  if (at == std::string::npos) return 0;
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + at, '\n'));
}

const char* JsonTypeName(const nlohmann::json& value) { return value.type_name(); }

Status JsonPositiveNumber(const nlohmann::json& object, const std::string& key,
                          const std::string& path, const std::string& what, const std::string& text,
                          const std::string& source, double* value) {
  const int line = LineOf(text, "\"" + key + "\"");
  if (!object.contains(key)) {
    return Status::Error(source + ": missing field \"" + path + "\" (" + what + ")");
  }
  const nlohmann::json& v = object.at(key);
  if (!v.is_number()) {
    return Status::Error(At(source, line) + "field \"" + path + "\" must be a number (" + what +
                         "), found " + JsonTypeName(v));
  }
  *value = v.get<double>();
  if (!std::isfinite(*value) || !(*value > 0.0)) {
    return Status::Error(At(source, line) + "field \"" + path + "\" must be positive and finite (" +
                         what + "), got " + Num(*value));
  }
  return Status::Ok();
}

// Where a run's odometry comes from, for messages.
std::string OdometryLines(const BearingRun& run) {
  const int first = run.odometry.front().line;
  const int last = run.odometry.back().line;
  if (first <= 0) return "";
  return " (odometry lines " + std::to_string(first) + "–" + std::to_string(last) + ")";
}

Status CheckRunOdometry(const BearingRun& run, const std::string& source) {
  if (run.odometry.size() < 2) {
    const int line = run.odometry.empty() ? 0 : run.odometry.front().line;
    return Status::Error(At(source, line) + "run " + std::to_string(run.id) + " has " +
                         std::to_string(run.odometry.size()) +
                         " encoder sample(s); at least two are needed");
  }
  for (size_t i = 0; i < run.odometry.size(); ++i) {
    const EncoderSample& e = run.odometry[i];
    const std::string where = At(source, e.line) + "run " + std::to_string(run.id) + ": ";
    if (!std::isfinite(e.t_s) || !std::isfinite(e.left_rad) || !std::isfinite(e.right_rad)) {
      return Status::Error(where + "encoder sample " + std::to_string(i) + " is not finite");
    }
    if (i > 0 && !(e.t_s > run.odometry[i - 1].t_s)) {
      const int prev = run.odometry[i - 1].line;
      return Status::Error(
          where + "t = " + Num(e.t_s) +
          " is not after the previous sample's t = " + Num(run.odometry[i - 1].t_s) +
          (prev > 0 ? " (line " + std::to_string(prev) + ")" : std::string()) +
          "; times must increase within a run");
    }
  }
  return Status::Ok();
}

Status CheckBearing(const BearingRun& run, size_t i, const std::string& source) {
  const BearingSample& b = run.bearings[i];
  const std::string where = At(source, b.line) + "run " + std::to_string(run.id) + ": ";
  if (!std::isfinite(b.t_s) || !std::isfinite(b.bearing_rad)) {
    return Status::Error(where + "bearing sample " + std::to_string(i) + " is not finite");
  }
  if (!(b.bearing_rad > -M_PI - kBearingSlack && b.bearing_rad <= M_PI + kBearingSlack)) {
    return Status::Error(where + "bearing " + Num(b.bearing_rad) +
                         " is outside (−π, π]; bearings are in radians, wrapped");
  }
  const double t0 = run.odometry.front().t_s;
  const double t1 = run.odometry.back().t_s;
  if (b.t_s < t0 || b.t_s > t1) {
    return Status::Error(where + "t = " + Num(b.t_s) +
                         " is outside the run's odometry time span [" + Num(t0) + ", " + Num(t1) +
                         "]" + OdometryLines(run) +
                         "; bearings must be taken while the encoders are logged");
  }
  if (i > 0 && !(b.t_s > run.bearings[i - 1].t_s)) {
    const int prev = run.bearings[i - 1].line;
    return Status::Error(where + "t = " + Num(b.t_s) + " is not after the previous bearing's t = " +
                         Num(run.bearings[i - 1].t_s) +
                         (prev > 0 ? " (line " + std::to_string(prev) + ")" : std::string()) +
                         "; times must increase within a run");
  }
  return Status::Ok();
}

Status CheckMeta(const BearingLogMeta& meta, const std::vector<BearingRun>& runs,
                 const std::string& source) {
  if (!(meta.wheel_radius_m > 0.0) || !std::isfinite(meta.wheel_radius_m)) {
    return Status::Error(source + ": wheel_radius must be positive and finite, got " +
                         Num(meta.wheel_radius_m));
  }
  if (!(meta.wheelbase_m > 0.0) || !std::isfinite(meta.wheelbase_m)) {
    return Status::Error(source + ": wheelbase must be positive and finite, got " +
                         Num(meta.wheelbase_m));
  }
  if (meta.initial_distance) {
    const InitialDistance& d = *meta.initial_distance;
    if (!(d.meters > 0.0) || !std::isfinite(d.meters)) {
      return Status::Error(source + ": initial_distance.meters must be positive and finite, got " +
                           Num(d.meters));
    }
    const bool found =
        std::any_of(runs.begin(), runs.end(), [&](const BearingRun& r) { return r.id == d.run; });
    if (!found) {
      return Status::Error(source + ": initial_distance.run = " + std::to_string(d.run) +
                           " names no run of the odometry");
    }
  }
  return Status::Ok();
}

}  // namespace

StatusOr<std::vector<BearingRun>> ParseBearingOdometryCsv(const std::string& text,
                                                          const std::string& source) {
  CsvTable table;
  std::vector<size_t> col;
  Status status = ReadCsv(text, source, {"run", "t", "left", "right"}, &table, &col);
  if (!status.ok()) return status;
  std::map<int, BearingRun> runs;
  for (const CsvRow& row : table.rows) {
    const std::string where = At(source, row.line);
    int id = 0;
    EncoderSample e;
    e.line = row.line;
    if (!(status = ParseRunId(row.fields[col[0]], where, &id)).ok()) return status;
    if (!(status = ParseDouble(row.fields[col[1]], "t", where, &e.t_s)).ok()) return status;
    if (!(status = ParseDouble(row.fields[col[2]], "left", where, &e.left_rad)).ok()) {
      return status;
    }
    if (!(status = ParseDouble(row.fields[col[3]], "right", where, &e.right_rad)).ok()) {
      return status;
    }
    BearingRun& run = runs[id];
    run.id = id;
    run.odometry.push_back(e);
  }
  std::vector<BearingRun> out;
  for (auto& [id, run] : runs) {
    if (!(status = CheckRunOdometry(run, source)).ok()) return status;
    out.push_back(std::move(run));
  }
  return out;
}

Status ParseBearingsCsv(const std::string& text, const std::string& source,
                        std::vector<BearingRun>* runs) {
  CsvTable table;
  std::vector<size_t> col;
  Status status = ReadCsv(text, source, {"run", "t", "bearing"}, &table, &col);
  if (!status.ok()) return status;
  for (const CsvRow& row : table.rows) {
    const std::string where = At(source, row.line);
    int id = 0;
    BearingSample b;
    b.line = row.line;
    if (!(status = ParseRunId(row.fields[col[0]], where, &id)).ok()) return status;
    if (!(status = ParseDouble(row.fields[col[1]], "t", where, &b.t_s)).ok()) return status;
    if (!(status = ParseDouble(row.fields[col[2]], "bearing", where, &b.bearing_rad)).ok()) {
      return status;
    }
    const auto run =
        std::find_if(runs->begin(), runs->end(), [&](const BearingRun& r) { return r.id == id; });
    if (run == runs->end()) {
      return Status::Error(where + "run " + std::to_string(id) + " has no encoder samples");
    }
    run->bearings.push_back(b);
    if (!(status = CheckBearing(*run, run->bearings.size() - 1, source)).ok()) return status;
  }
  for (const BearingRun& run : *runs) {
    if (run.bearings.empty()) {
      return Status::Error(source + ": run " + std::to_string(run.id) + " has no bearings" +
                           OdometryLines(run) + "; every run needs bearings of the landmark");
    }
  }
  return Status::Ok();
}

StatusOr<BearingLogMeta> ParseBearingMeta(const std::string& text, const std::string& source) {
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    // e.what() names the line and column.
    return Status::Error(source + ": not valid JSON: " + e.what());
  }
  if (!json.is_object()) {
    return Status::Error(source + ": expected a JSON object {\"wheel_radius\": m, " +
                         "\"wheelbase\": m}, found " + JsonTypeName(json));
  }
  BearingLogMeta meta;
  Status status =
      JsonPositiveNumber(json, "wheel_radius", "wheel_radius", "nominal wheel radius in metres",
                         text, source, &meta.wheel_radius_m);
  if (!status.ok()) return status;
  status = JsonPositiveNumber(json, "wheelbase", "wheelbase",
                              "nominal distance between the wheels in metres", text, source,
                              &meta.wheelbase_m);
  if (!status.ok()) return status;
  if (json.contains("initial_distance")) {
    const nlohmann::json& d = json.at("initial_distance");
    const int line = LineOf(text, "\"initial_distance\"");
    if (!d.is_object()) {
      return Status::Error(At(source, line) +
                           "field \"initial_distance\" must be an object {\"run\": R, " +
                           "\"meters\": D0}, found " + JsonTypeName(d));
    }
    InitialDistance initial;
    if (!d.contains("run")) {
      return Status::Error(At(source, line) +
                           "missing field \"initial_distance.run\" (the run whose start distance "
                           "is given)");
    }
    const nlohmann::json& run = d.at("run");
    const bool integral =
        run.is_number_integer() || (run.is_number_float() && std::isfinite(run.get<double>()) &&
                                    run.get<double>() == std::floor(run.get<double>()));
    if (!integral || std::abs(run.get<double>()) > 2e9) {
      return Status::Error(At(source, LineOf(text, "\"run\"")) +
                           "field \"initial_distance.run\" must be an integer run id, found " +
                           (run.is_number() ? Num(run.get<double>()) : JsonTypeName(run)));
    }
    initial.run = static_cast<int>(run.get<double>());
    status = JsonPositiveNumber(d, "meters", "initial_distance.meters",
                                "robot–landmark distance at the run's start in metres", text,
                                source, &initial.meters);
    if (!status.ok()) return status;
    meta.initial_distance = initial;
  }
  return meta;
}

Status ValidateBearingLog(const BearingLog& log) {
  const std::string& source = log.source.empty() ? std::string("bearing log") : log.source;
  if (log.runs.empty()) return Status::Error(source + ": no runs");
  for (size_t i = 0; i < log.runs.size(); ++i) {
    const BearingRun& run = log.runs[i];
    if (i > 0 && !(run.id > log.runs[i - 1].id)) {
      return Status::Error(source + ": run ids must be unique and increasing, run " +
                           std::to_string(run.id) + " follows run " +
                           std::to_string(log.runs[i - 1].id));
    }
    Status status = CheckRunOdometry(run, source + "/odometry.csv");
    if (!status.ok()) return status;
    if (run.bearings.empty()) {
      return Status::Error(source + "/bearings.csv: run " + std::to_string(run.id) +
                           " has no bearings" + OdometryLines(run));
    }
    for (size_t j = 0; j < run.bearings.size(); ++j) {
      if (!(status = CheckBearing(run, j, source + "/bearings.csv")).ok()) return status;
    }
  }
  return CheckMeta(log.meta, log.runs, source + "/meta.json");
}

StatusOr<BearingLog> ReadBearingLog(const std::string& directory) {
  std::error_code ec;
  if (!fs::is_directory(directory, ec)) {
    return Status::Error(directory + ": not a directory (a bearing log is a directory with " +
                         "odometry.csv, bearings.csv and meta.json)");
  }
  const std::string odometry_path = (fs::path(directory) / "odometry.csv").string();
  const std::string bearings_path = (fs::path(directory) / "bearings.csv").string();
  const std::string meta_path = (fs::path(directory) / "meta.json").string();
  std::string text;
  Status status = ReadWholeFile(odometry_path, &text);
  if (!status.ok()) return status;
  StatusOr<std::vector<BearingRun>> runs = ParseBearingOdometryCsv(text, odometry_path);
  if (!runs.ok()) return runs.status();
  if (!(status = ReadWholeFile(bearings_path, &text)).ok()) return status;
  if (!(status = ParseBearingsCsv(text, bearings_path, &*runs)).ok()) return status;
  if (!(status = ReadWholeFile(meta_path, &text)).ok()) return status;
  StatusOr<BearingLogMeta> meta = ParseBearingMeta(text, meta_path);
  if (!meta.ok()) return meta.status();
  if (!(status = CheckMeta(*meta, *runs, meta_path)).ok()) return status;
  BearingLog log;
  log.source = directory;
  log.meta = *meta;
  log.runs = std::move(*runs);
  return log;
}

Status WriteBearingLog(const BearingLog& log, const std::string& directory) {
  std::error_code ec;
  fs::create_directories(directory, ec);
  if (ec) return Status::Error(directory + ": cannot create directory: " + ec.message());
  std::string odometry = "run,t,left,right\n";
  std::string bearings = "run,t,bearing\n";
  for (const BearingRun& run : log.runs) {
    const std::string id = std::to_string(run.id) + ",";
    for (const EncoderSample& e : run.odometry) {
      odometry += id + Num(e.t_s) + "," + Num(e.left_rad) + "," + Num(e.right_rad) + "\n";
    }
    for (const BearingSample& b : run.bearings) {
      bearings += id + Num(b.t_s) + "," + Num(b.bearing_rad) + "\n";
    }
  }
  nlohmann::json meta = {{"wheel_radius", log.meta.wheel_radius_m},
                         {"wheelbase", log.meta.wheelbase_m}};
  if (log.meta.initial_distance) {
    meta["initial_distance"] = {{"run", log.meta.initial_distance->run},
                                {"meters", log.meta.initial_distance->meters}};
  }
  Status status = WriteWholeFile((fs::path(directory) / "odometry.csv").string(), odometry);
  if (!status.ok()) return status;
  status = WriteWholeFile((fs::path(directory) / "bearings.csv").string(), bearings);
  if (!status.ok()) return status;
  return WriteWholeFile((fs::path(directory) / "meta.json").string(), meta.dump(2) + "\n");
}

}  // namespace calib
