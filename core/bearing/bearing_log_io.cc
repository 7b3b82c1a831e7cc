#include <calib/core/bearing/bearing_log_io.h>
#include <calib/core/csv.h>
#include <calib/core/encoder_spikes.h>
#include <calib/core/text_file.h>
#include <calib/core/text_number.h>
#include <calib/core/timing/stamp_timing.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string_view>
#include <system_error>
#include <utility>

namespace calib {
namespace {

namespace fs = std::filesystem;

// A bearing this far beyond ±π is still taken as wrapped (rounding in the writer's own output).
constexpr double kBearingSlack = 1e-9;

// One warning for the exact duplicates (same stamp and values as the record before) dropped.
void WarnDuplicates(const std::string& source, int duplicates, std::vector<std::string>* warnings) {
  if (duplicates == 0 || warnings == nullptr) return;
  warnings->push_back(source + ": " + std::to_string(duplicates) +
                      " exact duplicate record(s) dropped (same stamp and values as the record "
                      "before)");
}

std::string At(const std::string& source, int64_t line) {
  return line > 0 ? source + ":" + std::to_string(line) + ": " : source + ": ";
}

// "no samples after the header (line 1)" when the reader saw no record.
Status NoSamples(const CsvReader& csv) {
  return Status::InvalidInput(csv.source() + ": no samples after the header (line " +
                              std::to_string(csv.header_line()) + ")");
}

// The 1-based line of the first occurrence of `needle` in `text` (0 if absent).
int64_t LineOf(std::string_view text, const std::string& needle) {
  const size_t at = text.find(needle);
  if (at == std::string_view::npos) return 0;
  return 1 + std::count(text.begin(), text.begin() + at, '\n');
}

const char* JsonTypeName(const nlohmann::json& value) { return value.type_name(); }

// A positive length at most `largest_m` (no robot's wheel is 10 m, no landmark seen 100 km away).
Status JsonPositiveNumber(const nlohmann::json& object, const std::string& key,
                          const std::string& path, const std::string& what, double largest_m,
                          std::string_view text, const std::string& source, double* value) {
  const int64_t line = LineOf(text, "\"" + key + "\"");
  if (!object.contains(key)) {
    return Status::InvalidInput(source + ": missing field \"" + path + "\" (" + what + ")");
  }
  const nlohmann::json& v = object.at(key);
  if (!v.is_number()) {
    return Status::InvalidInput(At(source, line) + "field \"" + path + "\" must be a number (" +
                                what + "), found " + JsonTypeName(v));
  }
  *value = v.get<double>();
  if (!std::isfinite(*value) || !(*value > 0.0)) {
    return Status::InvalidInput(At(source, line) + "field \"" + path +
                                "\" must be positive and finite (" + what + "), got " +
                                Num(*value));
  }
  if (*value > largest_m) {
    return Status::InvalidInput(At(source, line) + "field \"" + path + "\" is " + Num(*value) +
                                " m, more than the " + Num(largest_m) + " m it can be (" + what +
                                ")");
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
    return Status::InvalidInput(At(source, line) + "run " + std::to_string(run.id) + " has " +
                                std::to_string(run.odometry.size()) +
                                " encoder sample(s); at least two are needed");
  }
  for (size_t i = 0; i < run.odometry.size(); ++i) {
    const EncoderSample& e = run.odometry[i];
    const std::string where = At(source, e.line) + "run " + std::to_string(run.id) + ": ";
    if (!std::isfinite(e.t_s) || !std::isfinite(e.left_rad) || !std::isfinite(e.right_rad)) {
      return Status::InvalidInput(where + "encoder sample " + std::to_string(i) + " is not finite");
    }
    if (i > 0 && !(e.t_s > run.odometry[i - 1].t_s)) {
      const int prev = run.odometry[i - 1].line;
      return Status::InvalidInput(
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
    return Status::InvalidInput(where + "bearing sample " + std::to_string(i) + " is not finite");
  }
  if (!(b.bearing_rad > -M_PI - kBearingSlack && b.bearing_rad <= M_PI + kBearingSlack)) {
    return Status::InvalidInput(where + "bearing " + Num(b.bearing_rad) +
                                " is outside (−π, π]; bearings are in radians, wrapped");
  }
  const double t0 = run.odometry.front().t_s;
  const double t1 = run.odometry.back().t_s;
  if (b.t_s < t0 || b.t_s > t1) {
    return Status::InvalidInput(where + "t = " + Num(b.t_s) +
                                " is outside the run's odometry time span [" + Num(t0) + ", " +
                                Num(t1) + "]" + OdometryLines(run) +
                                "; bearings must be taken while the encoders are logged");
  }
  if (i > 0 && !(b.t_s > run.bearings[i - 1].t_s)) {
    const int prev = run.bearings[i - 1].line;
    return Status::InvalidInput(
        where + "t = " + Num(b.t_s) +
        " is not after the previous bearing's t = " + Num(run.bearings[i - 1].t_s) +
        (prev > 0 ? " (line " + std::to_string(prev) + ")" : std::string()) +
        "; times must increase within a run");
  }
  return Status::Ok();
}

// A bearing no sensor gives (outside (−π, π]) or taken outside its run's odometry.
bool IsGlitch(const BearingRun& run, const BearingSample& b) {
  return !(b.bearing_rad > -M_PI - kBearingSlack && b.bearing_rad <= M_PI + kBearingSlack) ||
         !(b.t_s >= run.odometry.front().t_s && b.t_s <= run.odometry.back().t_s);
}

// A handful of such bearings (one in 50 at most) are glitches: dropped, one warning naming the
// first. More are the file's unit or clock, not glitches: kept, for CheckBearing to refuse.
void DropIsolatedGlitches(const std::string& source, std::vector<BearingRun>* runs,
                          std::vector<std::string>* warnings) {
  size_t total = 0, glitches = 0;
  std::string first;
  for (const BearingRun& run : *runs) {
    total += run.bearings.size();
    for (const BearingSample& b : run.bearings) {
      if (!IsGlitch(run, b)) continue;
      if (glitches++ == 0) {
        first = At(source, b.line) + "run " + std::to_string(run.id) + ": t = " + Num(b.t_s) +
                ", bearing " + Num(b.bearing_rad);
      }
    }
  }
  if (glitches == 0 || glitches > total / 50) return;
  for (BearingRun& run : *runs) {
    std::vector<BearingSample> kept;
    for (const BearingSample& b : run.bearings) {
      if (!IsGlitch(run, b)) kept.push_back(b);
    }
    run.bearings = std::move(kept);
  }
  if (warnings != nullptr) {
    warnings->push_back(source + ": " + std::to_string(glitches) +
                        " bearing(s) dropped: outside (−π, π] or outside their run's odometry "
                        "(first: " +
                        first + ")");
  }
}

Status CheckMeta(const BearingLogMeta& meta, const std::vector<BearingRun>& runs,
                 const std::string& source) {
  if (!(meta.wheel_radius_m > 0.0) || !std::isfinite(meta.wheel_radius_m)) {
    return Status::InvalidInput(source + ": wheel_radius must be positive and finite, got " +
                                Num(meta.wheel_radius_m));
  }
  if (!(meta.wheelbase_m > 0.0) || !std::isfinite(meta.wheelbase_m)) {
    return Status::InvalidInput(source + ": wheelbase must be positive and finite, got " +
                                Num(meta.wheelbase_m));
  }
  if (meta.initial_distance) {
    const InitialDistance& d = *meta.initial_distance;
    if (!(d.meters > 0.0) || !std::isfinite(d.meters)) {
      return Status::InvalidInput(
          source + ": initial_distance.meters must be positive and finite, got " + Num(d.meters));
    }
    const bool found =
        std::any_of(runs.begin(), runs.end(), [&](const BearingRun& r) { return r.id == d.run; });
    if (!found) {
      return Status::InvalidInput(source + ": initial_distance.run = " + std::to_string(d.run) +
                                  " names no run of the odometry");
    }
  }
  return Status::Ok();
}

StatusOr<std::vector<BearingRun>> ParseOdometry(std::string_view text, const std::string& source,
                                                StreamTiming* timing,
                                                std::vector<std::string>* warnings) {
  CALIB_ASSIGN_OR_RETURN(CsvReader csv,
                         CsvReader::Open(text, source, {{"run"}, {"t"}, {"left"}, {"right"}}));
  std::map<int, StreamRecords> records;  // Per run, in file order.
  while (true) {
    CALIB_ASSIGN_OR_RETURN(const bool more, csv.Next());
    if (!more) break;
    int id = 0;
    double t = 0.0, left = 0.0, right = 0.0;
    CALIB_RETURN_IF_ERROR(csv.Integer(0, &id, "an integer run id"));
    CALIB_RETURN_IF_ERROR(csv.Number(1, &t));
    CALIB_RETURN_IF_ERROR(csv.Number(2, &left));
    CALIB_RETURN_IF_ERROR(csv.Number(3, &right));
    StreamRecords& run = records[id];
    run.stamps_s.push_back(t);
    run.values.insert(run.values.end(), {left, right});
    run.lines.push_back(SaturatedInt(csv.line()));
  }
  if (records.empty()) return NoSamples(csv);
  std::vector<BearingRun> out;
  std::vector<StreamTiming> timings;
  int duplicates = 0;
  for (auto& [id, given] : records) {
    if (timing != nullptr) {
      timings.push_back(AnalyzeStreamTiming(given.stamps_s, given.values, "odometry",
                                            source + " run " + std::to_string(id)));
    }
    StreamRecords kept = std::move(given);
    CALIB_RETURN_IF_ERROR(CheckStampUnit(kept.stamps_s, source + " run " + std::to_string(id)));
    kept.value_names = {"left", "right"};
    int dropped = 0;
    CALIB_RETURN_IF_ERROR(DropExactDuplicates(source, &kept, &dropped));
    duplicates += dropped;
    BearingRun run;
    run.id = id;
    for (size_t k = 0; k < kept.stamps_s.size(); ++k) {
      run.odometry.push_back(EncoderSample{kept.stamps_s[k], kept.values[2 * k],
                                           kept.values[2 * k + 1], kept.lines[k]});
    }
    int first_line = 0;
    if (const int spikes = DropEncoderSpikes(&run.odometry, &first_line);
        spikes > 0 && warnings != nullptr) {
      warnings->push_back(At(source, first_line) + "run " + std::to_string(id) + ": " +
                          std::to_string(spikes) +
                          " encoder sample(s) dropped: the wheel angle jumps away and back (a "
                          "logging glitch)");
    }
    CALIB_RETURN_IF_ERROR(CheckRunOdometry(run, source));
    out.push_back(std::move(run));
  }
  if (timing != nullptr) *timing = PoolStreamTiming(timings, "odometry", source);
  WarnDuplicates(source, duplicates, warnings);
  return out;
}

Status ParseBearings(std::string_view text, const std::string& source,
                     std::vector<BearingRun>* runs, StreamTiming* timing,
                     std::vector<std::string>* warnings) {
  CALIB_ASSIGN_OR_RETURN(CsvReader csv,
                         CsvReader::Open(text, source, {{"run"}, {"t"}, {"bearing"}}));
  std::map<int, StreamRecords> records;  // Per run, in file order.
  while (true) {
    CALIB_ASSIGN_OR_RETURN(const bool more, csv.Next());
    if (!more) break;
    int id = 0;
    double t = 0.0, bearing = 0.0;
    CALIB_RETURN_IF_ERROR(csv.Integer(0, &id, "an integer run id"));
    CALIB_RETURN_IF_ERROR(csv.Number(1, &t));
    CALIB_RETURN_IF_ERROR(csv.Number(2, &bearing));
    // Runs are sorted by id: a search, not a scan per record.
    const auto run_at = std::lower_bound(runs->begin(), runs->end(), id,
                                         [](const BearingRun& r, int key) { return r.id < key; });
    if (run_at == runs->end() || run_at->id != id) {
      return Status::InvalidInput(At(source, csv.line()) + "run " + std::to_string(id) +
                                  " has no encoder samples");
    }
    StreamRecords& run = records[id];
    run.stamps_s.push_back(t);
    run.values.push_back(bearing);
    run.lines.push_back(SaturatedInt(csv.line()));
  }
  if (records.empty()) return NoSamples(csv);
  std::vector<StreamTiming> timings;
  int duplicates = 0;
  for (BearingRun& run : *runs) {
    const auto found = records.find(run.id);
    if (found == records.end()) continue;  // Refused below, in the runs' order.
    StreamRecords& kept = found->second;
    if (timing != nullptr) {
      timings.push_back(AnalyzeStreamTiming(kept.stamps_s, kept.values, "bearings",
                                            source + " run " + std::to_string(run.id)));
    }
    kept.value_names = {"bearing"};
    int dropped = 0;
    CALIB_RETURN_IF_ERROR(DropExactDuplicates(source, &kept, &dropped));
    duplicates += dropped;
    for (size_t k = 0; k < kept.stamps_s.size(); ++k) {
      run.bearings.push_back(BearingSample{kept.stamps_s[k], kept.values[k], kept.lines[k]});
    }
  }
  WarnDuplicates(source, duplicates, warnings);
  DropIsolatedGlitches(source, runs, warnings);
  for (const BearingRun& run : *runs) {
    if (records.count(run.id) == 0) {
      return Status::InvalidInput(source + ": run " + std::to_string(run.id) + " has no bearings" +
                                  OdometryLines(run) +
                                  "; every run needs bearings of the landmark");
    }
    for (size_t k = 0; k < run.bearings.size(); ++k) {
      CALIB_RETURN_IF_ERROR(CheckBearing(run, k, source));
    }
  }
  if (timing != nullptr) *timing = PoolStreamTiming(timings, "bearings", source);
  return Status::Ok();
}

StatusOr<BearingLogMeta> ParseMeta(std::string_view text, const std::string& source) {
  nlohmann::json json;
  try {
    json = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    // e.what() names the line and column.
    return Status::InvalidInput(source + ": not valid JSON: " + e.what());
  }
  if (!json.is_object()) {
    return Status::InvalidInput(source + ": expected a JSON object {\"wheel_radius\": m, " +
                                "\"wheelbase\": m}, found " + JsonTypeName(json));
  }
  BearingLogMeta meta;
  CALIB_RETURN_IF_ERROR(JsonPositiveNumber(json, "wheel_radius", "wheel_radius",
                                           "nominal wheel radius in metres", 10.0, text, source,
                                           &meta.wheel_radius_m));
  CALIB_RETURN_IF_ERROR(JsonPositiveNumber(json, "wheelbase", "wheelbase",
                                           "nominal distance between the wheels in metres", 100.0,
                                           text, source, &meta.wheelbase_m));
  if (json.contains("initial_distance")) {
    const nlohmann::json& d = json.at("initial_distance");
    const int64_t line = LineOf(text, "\"initial_distance\"");
    if (!d.is_object()) {
      return Status::InvalidInput(At(source, line) +
                                  "field \"initial_distance\" must be an object {\"run\": R, " +
                                  "\"meters\": D0}, found " + JsonTypeName(d));
    }
    InitialDistance initial;
    if (!d.contains("run")) {
      return Status::InvalidInput(
          At(source, line) +
          "missing field \"initial_distance.run\" (the run whose start distance "
          "is given)");
    }
    const nlohmann::json& run = d.at("run");
    const bool integral =
        run.is_number_integer() || (run.is_number_float() && std::isfinite(run.get<double>()) &&
                                    run.get<double>() == std::floor(run.get<double>()));
    if (!integral || std::abs(run.get<double>()) > 2e9) {
      return Status::InvalidInput(
          At(source, LineOf(text, "\"run\"")) +
          "field \"initial_distance.run\" must be an integer run id, found " +
          (run.is_number() ? Num(run.get<double>()) : JsonTypeName(run)));
    }
    initial.run = static_cast<int>(run.get<double>());
    CALIB_RETURN_IF_ERROR(JsonPositiveNumber(d, "meters", "initial_distance.meters",
                                             "robot–landmark distance at the run's start in metres",
                                             1e5, text, source, &initial.meters));
    meta.initial_distance = initial;
  }
  return meta;
}

}  // namespace

StatusOr<std::vector<BearingRun>> ParseBearingOdometryCsv(std::string_view text,
                                                          const std::string& source,
                                                          StreamTiming* timing,
                                                          std::vector<std::string>* warnings) {
  return GuardAllocation(source, [&] { return ParseOdometry(text, source, timing, warnings); });
}

Status ParseBearingsCsv(std::string_view text, const std::string& source,
                        std::vector<BearingRun>* runs, StreamTiming* timing,
                        std::vector<std::string>* warnings) {
  return GuardAllocation(source,
                         [&] { return ParseBearings(text, source, runs, timing, warnings); });
}

StatusOr<BearingLogMeta> ParseBearingMeta(std::string_view text, const std::string& source) {
  return GuardAllocation(source, [&] { return ParseMeta(text, source); });
}

Status ValidateBearingLog(const BearingLog& log) {
  const std::string& source = log.source.empty() ? std::string("bearing log") : log.source;
  if (log.runs.empty()) return Status::InvalidInput(source + ": no runs");
  for (size_t i = 0; i < log.runs.size(); ++i) {
    const BearingRun& run = log.runs[i];
    if (i > 0 && !(run.id > log.runs[i - 1].id)) {
      return Status::InvalidInput(source + ": run ids must be unique and increasing, run " +
                                  std::to_string(run.id) + " follows run " +
                                  std::to_string(log.runs[i - 1].id));
    }
    CALIB_RETURN_IF_ERROR(CheckRunOdometry(run, source + "/odometry.csv"));
    if (run.bearings.empty()) {
      return Status::InvalidInput(source + "/bearings.csv: run " + std::to_string(run.id) +
                                  " has no bearings" + OdometryLines(run));
    }
    for (size_t j = 0; j < run.bearings.size(); ++j) {
      CALIB_RETURN_IF_ERROR(CheckBearing(run, j, source + "/bearings.csv"));
    }
  }
  return CheckMeta(log.meta, log.runs, source + "/meta.json");
}

namespace {

StatusOr<BearingLog> ParseLog(std::string_view odometry_csv, std::string_view bearings_csv,
                              const std::function<StatusOr<std::string_view>()>& meta_json,
                              const std::string& directory) {
  const std::string odometry_path = (fs::path(directory) / "odometry.csv").string();
  const std::string bearings_path = (fs::path(directory) / "bearings.csv").string();
  const std::string meta_path = (fs::path(directory) / "meta.json").string();
  std::vector<StreamTiming> timing(2);
  std::vector<std::string> warnings;
  CALIB_ASSIGN_OR_RETURN(
      std::vector<BearingRun> runs,
      ParseBearingOdometryCsv(odometry_csv, odometry_path, &timing[0], &warnings));
  CALIB_RETURN_IF_ERROR(
      ParseBearingsCsv(bearings_csv, bearings_path, &runs, &timing[1], &warnings));
  CALIB_ASSIGN_OR_RETURN(const std::string_view meta_text, meta_json());
  if (meta_text.size() > kMaxLineBytes) {
    return Status::InvalidInput(meta_path + ": " + std::to_string(meta_text.size()) +
                                " bytes, more than the " + std::to_string(kMaxLineBytes) +
                                " a meta file of a few numbers may have");
  }
  CALIB_ASSIGN_OR_RETURN(const BearingLogMeta meta, ParseBearingMeta(meta_text, meta_path));
  CALIB_RETURN_IF_ERROR(CheckMeta(meta, runs, meta_path));
  return GuardAllocation(directory, [&]() -> StatusOr<BearingLog> {
    BearingLog log;
    log.source = directory;
    log.meta = meta;
    log.runs = std::move(runs);
    log.stream_timing = std::move(timing);
    log.warnings = std::move(warnings);
    return log;
  });
}

}  // namespace

StatusOr<BearingLog> ReadBearingLog(const std::string& directory) {
  std::error_code ec;
  if (!fs::is_directory(directory, ec)) {
    return Status::Io(directory + ": not a directory (a bearing log is a directory with " +
                      "odometry.csv, bearings.csv and meta.json)");
  }
  // Each file opened when its turn comes, so that the first problem is the one named.
  CALIB_ASSIGN_OR_RETURN(const MappedFile odometry,
                         MappedFile::OpenText((fs::path(directory) / "odometry.csv").string()));
  StatusOr<MappedFile> bearings =
      MappedFile::OpenText((fs::path(directory) / "bearings.csv").string());
  MappedFile meta;
  const auto read_meta = [&]() -> StatusOr<std::string_view> {
    CALIB_ASSIGN_OR_RETURN(meta,
                           MappedFile::OpenText((fs::path(directory) / "meta.json").string()));
    return meta.text();
  };
  if (!bearings.ok()) {
    // The odometry's problems come first; a missing bearings.csv after them.
    CALIB_RETURN_IF_ERROR(
        ParseBearingOdometryCsv(odometry.text(), (fs::path(directory) / "odometry.csv").string()));
    return bearings.status();
  }
  return ParseLog(odometry.text(), bearings->text(), read_meta, directory);
}

StatusOr<BearingLog> ParseBearingLog(std::string_view odometry_csv, std::string_view bearings_csv,
                                     std::string_view meta_json, const std::string& directory) {
  return ParseLog(
      odometry_csv, bearings_csv, [&]() -> StatusOr<std::string_view> { return meta_json; },
      directory);
}

Status WriteBearingLog(const BearingLog& log, const std::string& directory) {
  std::error_code ec;
  fs::create_directories(directory, ec);
  if (ec) return Status::Io(directory + ": cannot create directory: " + ec.message());
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
  CALIB_RETURN_IF_ERROR(WriteWholeFile((fs::path(directory) / "odometry.csv").string(), odometry));
  CALIB_RETURN_IF_ERROR(WriteWholeFile((fs::path(directory) / "bearings.csv").string(), bearings));
  return WriteWholeFile((fs::path(directory) / "meta.json").string(), meta.dump(2) + "\n");
}

}  // namespace calib
