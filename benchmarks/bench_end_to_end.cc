#include "benchmarks/bench_end_to_end.h"

#include <algorithm>
#include <filesystem>
#include <vector>

#include "benchmarks/bench_process.h"

namespace calib::bench {
namespace {

namespace fs = std::filesystem;

struct Program {
  std::string name;
  std::string binary;
  std::string args;
  std::vector<ProcessRun> runs;
};

// The per-run figures a summary covers: JSON key, table scale and format.
struct Metric {
  const char* key;
  double (*get)(const ProcessRun&);
  double scale;
  const char* format;
};

const Metric kMetrics[] = {
    {"wall_s", [](const ProcessRun& r) { return r.wall_s; }, 1.0, "%.3f"},
    {"cpu_s", [](const ProcessRun& r) { return r.cpu_s; }, 1.0, "%.3f"},
    {"maxrss_kb", [](const ProcessRun& r) { return double(r.maxrss_kb); }, 1.0 / 1024, "%.1f"},
    {"minflt", [](const ProcessRun& r) { return double(r.minflt); }, 1.0, "%.0f"},
    {"majflt", [](const ProcessRun& r) { return double(r.majflt); }, 1.0, "%.0f"},
};

std::vector<double> Values(const std::vector<ProcessRun>& runs, const Metric& metric) {
  std::vector<double> values;
  for (const ProcessRun& run : runs) {
    if (run.ok()) values.push_back(metric.get(run));
  }
  return values;
}

// min and median of each metric over the successful runs; null when none succeeded.
nlohmann::json Summary(const Program& program) {
  nlohmann::json j;
  for (const Metric& metric : kMetrics) {
    const std::vector<double> values = Values(program.runs, metric);
    if (values.empty()) return nullptr;
    j[metric.key] = {{"min", *std::min_element(values.begin(), values.end())},
                     {"median", Median(values)}};
  }
  return j;
}

std::string FirstError(const Program& program) {
  for (const ProcessRun& run : program.runs) {
    if (run.ok()) continue;
    std::string text = run.error;
    if (!run.stderr_tail.empty()) text += "; stderr: " + run.stderr_tail;
    return text;
  }
  return "";
}

void AddRows(const std::string& label, const Program& program, const nlohmann::json& summary,
             EndToEndReport* report) {
  int ok = 0;
  for (const ProcessRun& run : program.runs) ok += run.ok();
  const std::string count = Format("%d/%zu", ok, program.runs.size());
  if (summary.is_null()) {
    report->table.AddRow(
        {label, program.name, count,
         "FAILED " + report->AddNote(program.name + " on " + label + ": " + FirstError(program))});
    return;
  }
  std::vector<std::string> row = {label, program.name, count};
  for (const Metric& metric : kMetrics) {
    for (const char* stat : {"min", "median"}) {
      row.push_back(Format(metric.format, summary[metric.key][stat].get<double>() * metric.scale));
    }
  }
  if (ok < static_cast<int>(program.runs.size())) {
    row[2] += " " + report->AddNote(program.name + " on " + label + ": " + FirstError(program));
  }
  report->table.AddRow(row);
}

// calib/peer for each metric's min and median; a zero denominator gives null.
nlohmann::json Ratios(const nlohmann::json& calib, const nlohmann::json& peer, TextTable* table) {
  nlohmann::json j;
  std::vector<std::string> row = {"", "calib/peer", ""};
  for (const Metric& metric : kMetrics) {
    for (const char* stat : {"min", "median"}) {
      const double num = calib[metric.key][stat].get<double>();
      const double den = peer[metric.key][stat].get<double>();
      if (den > 0) {
        j[metric.key][stat] = num / den;
        row.push_back(Format("%.3f", num / den));
      } else {
        j[metric.key][stat] = nullptr;
        row.push_back("-");
      }
    }
  }
  table->AddRow(row);
  return j;
}

}  // namespace

EndToEndReport::EndToEndReport()
    : table({"input", "program", "ok", "wall min s", "wall med s", "CPU min s", "CPU med s",
             "peak min MB", "peak med MB", "minflt min", "minflt med", "majflt min",
             "majflt med"}) {}

std::string EndToEndReport::AddNote(const std::string& note) {
  notes.push_back(note);
  return Format("[%zu]", notes.size());
}

void EndToEndReport::Print() const {
  table.Print();
  for (size_t i = 0; i < notes.size(); ++i) std::printf("  [%zu] %s\n", i + 1, notes[i].c_str());
}

nlohmann::json RunEndToEnd(const EndToEndOptions& options, const std::string& label,
                           const std::string& input, int reps, const std::string& peer_skip_reason,
                           EndToEndReport* report) {
  std::vector<Program> programs = {{"calib", options.calib_cli, options.calib_args, {}}};
  const bool with_peer = !options.peer_solver.empty() && peer_skip_reason.empty();
  if (with_peer) programs.push_back({"peer", options.peer_solver, options.peer_args, {}});
  for (int rep = 0; rep < reps; ++rep) {
    for (Program& program : programs) {
      const fs::path dir = fs::path(options.work_dir) / program.name;
      fs::create_directories(dir);
      const std::string output = (dir / "result.json").string();
      std::vector<std::string> argv = {program.binary};
      for (const std::string& arg :
           ExpandArgs(program.args, {{"input", input}, {"output", output}})) {
        argv.push_back(arg);
      }
      program.runs.push_back(RunThroughLauncher(options.launcher, argv, dir.string(), output));
    }
  }
  nlohmann::json out = {{"input", input}, {"reps", reps}};
  std::vector<nlohmann::json> summaries;
  for (const Program& program : programs) {
    nlohmann::json runs = nlohmann::json::array();
    for (const ProcessRun& run : program.runs) runs.push_back(ToJson(run));
    summaries.push_back(Summary(program));
    out[program.name] = {{"binary", program.binary},
                         {"args", program.args},
                         {"runs", runs},
                         {"summary", summaries.back()}};
    if (summaries.back().is_null()) out[program.name]["error"] = FirstError(program);
    AddRows(label, program, summaries.back(), report);
  }
  if (!peer_skip_reason.empty() && !options.peer_solver.empty()) {
    out["peer_skipped"] = peer_skip_reason;
    report->table.AddRow(
        {label, "peer", "-",
         "skipped " + report->AddNote("peer on " + label + ": " + peer_skip_reason)});
  }
  if (with_peer && !summaries[0].is_null() && !summaries[1].is_null()) {
    out["ratio_calib_over_peer"] = Ratios(summaries[0], summaries[1], &report->table);
  }
  report->table.AddRule();
  return out;
}

}  // namespace calib::bench
