#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <tuple>

#include "benchmarks/bench_end_to_end.h"
#include "benchmarks/bench_floor.h"
#include "benchmarks/bench_process.h"
#include "benchmarks/bench_sections.h"

namespace calib::bench {
namespace {

namespace fs = std::filesystem;

long MaxRssKb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;  // Linux: kB.
}

// The process's peak resident set, from /proc/self/status; -1 when unavailable.
long VmHwmKb() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::stol(line.substr(6));
  }
  return -1;
}

// Runs `command` and returns the last line of its stdout that starts with '{'.
StatusOr<nlohmann::json> RunChild(const std::string& command) {
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return Status::Io("cannot run " + command);
  std::string last, line;
  char buffer[4096];
  while (std::fgets(buffer, sizeof(buffer), pipe) != nullptr) {
    line += buffer;
    if (line.back() != '\n') continue;
    if (line[0] == '{') last = line;
    line.clear();
  }
  const int status = pclose(pipe);
  if (status != 0 || last.empty()) {
    return Status::Internal("child failed (status " + std::to_string(status) + "): " + command);
  }
  const nlohmann::json j = nlohmann::json::parse(last, nullptr, false);
  if (j.is_discarded()) return Status::Internal("child printed bad JSON: " + last);
  return j;
}

}  // namespace

int RunSpeedChild(const std::string& path, int64_t intervals) {
  const long rss_before = MaxRssKb();
  const Stopwatch watch;
  const StatusOr<LaserLog> log = ReadLaserLog(path);
  const double parse_s = watch.Seconds();
  if (!log.ok() || static_cast<int64_t>(log->intervals.size()) != intervals) {
    std::fprintf(stderr, "parse failed: %s\n", log.ok() ? "wrong count" : log.message().c_str());
    return 1;
  }
  const Stopwatch calibrate_watch;
  const StatusOr<LaserCalibrationResult> result = CalibrateLaser(log->intervals);
  const double calibrate_s = calibrate_watch.Seconds();
  if (!result.ok()) {
    std::fprintf(stderr, "calibration failed: %s\n", result.message().c_str());
    return 1;
  }
  const nlohmann::json j = {{"intervals", intervals},
                            {"parse_s", parse_s},
                            {"closed_form_s", result->closed_form_seconds},
                            {"refinement_s", result->refinement_seconds},
                            {"covariance_s", result->covariance_seconds},
                            {"calibrate_s", calibrate_s},
                            {"total_s", parse_s + calibrate_s},
                            {"iterations", result->iterations},
                            {"inliers", result->inliers},
                            {"maxrss_before_kb", rss_before},
                            {"maxrss_after_kb", MaxRssKb()},
                            {"vmhwm_kb", VmHwmKb()}};
  std::printf("%s\n", j.dump().c_str());
  return 0;
}

namespace {

// Rounds per size: fewer where one run takes long.
int RepsFor(int64_t n, int reps) {
  if (n <= 100000) return reps;
  return n <= 1000000 ? std::min(reps, 3) : 1;
}

// The `calib` binary and argument patterns; calib_cli empty when it is not found.
EndToEndOptions MakeEndToEndOptions(const BenchConfig& config, const fs::path& dir) {
  EndToEndOptions options;
  options.launcher = config.self_path;
  options.calib_cli = config.calib_cli.empty()
                          ? (fs::path(config.self_path).parent_path() / "calib").string()
                          : config.calib_cli;
  options.calib_args = config.calib_args;
  options.peer_solver = config.peer_solver;
  options.peer_args = config.peer_args;
  options.work_dir = (dir / "end_to_end").string();
  if (!fs::exists(options.calib_cli)) {
    std::printf(
        "End-to-end runs skipped: no calib CLI at %s (build the `calib` target or pass "
        "--calib_cli).\n",
        options.calib_cli.c_str());
    options.calib_cli.clear();
  }
  return options;
}

// What the previous size used, to tell whether ten times as many intervals fit in memory.
struct SizeFootprint {
  int64_t n = 0;
  long calib_kb = 0;  // The speed child's peak (VmHWM) or calib's, whichever is larger.
  long peer_kb = 0;
  long file_kb = 0;
  long simulate_kb = 0;  // This process's RSS growth while simulating and writing.
};

// Empty when `n` fits; else why not. `peer_reason` likewise for the peer alone.
std::string MemoryCheck(int64_t n, const SizeFootprint& last, const fs::path& dir,
                        std::string* peer_reason) {
  if (n <= 1000000 || last.n == 0) return "";
  const double scale = static_cast<double>(n) / last.n;
  const long available = MemAvailableKb();
  const double calib_kb = scale * (last.calib_kb + last.simulate_kb + last.file_kb);
  const double peer_kb = scale * (last.peer_kb + last.simulate_kb + last.file_kb);
  const double file_bytes = scale * last.file_kb * 1024.0;
  std::error_code error;
  const double disk = static_cast<double>(fs::space(dir, error).available);
  if (!error && disk < 1.5 * file_bytes) {
    return Format("the file needs about %.1f GB, %.1f GB free on %s", file_bytes / 1e9, disk / 1e9,
                  dir.c_str());
  }
  if (available < 0) return "MemAvailable is unknown";
  const auto gb = [](double kb) { return kb * 1024 / 1e9; };
  if (available < 1.25 * calib_kb) {
    return Format(
        "needs about %.1f GB (%gx the last size's peak, simulation and file), "
        "MemAvailable %.1f GB",
        gb(calib_kb), scale, gb(available));
  }
  if (last.peer_kb > 0 && available < 1.25 * peer_kb) {
    *peer_reason = Format("needs about %.1f GB (%gx its peak at %lld), MemAvailable %.1f GB",
                          gb(peer_kb), scale, static_cast<long long>(last.n), gb(available));
  }
  return "";
}

long SummaryMin(const nlohmann::json& e2e, const char* program, const char* key) {
  if (!e2e.contains(program) || e2e[program]["summary"].is_null()) return 0;
  return static_cast<long>(e2e[program]["summary"][key]["min"].get<double>());
}

}  // namespace

nlohmann::json RunSpeed(const BenchConfig& config) {
  std::printf("\n=== Section speed: wall time and peak memory against N ===\n");
  std::vector<int64_t> sizes = {1000, 10000, 100000};
  if (!config.quick) sizes.insert(sizes.end(), {1000000, 10000000});
  const int reps = config.speed_reps > 0 ? config.speed_reps : config.quick ? 3 : 7;
  std::printf(
      "Log: SimulateLaserLog seed 1 (rich trajectory, default noise, no outliers, "
      "speed_time_constant_s=0), written with WriteLaserTuples (without \"t\": the keys of the "
      "published files) to a temp dir.\n"
      "Each N runs in a fresh child process (%s --speed_child=N): ReadLaserLog, then "
      "CalibrateLaser with defaults (Ceres 2 threads).\nStage times are "
      "CalibrateLaser's own; total = parse + CalibrateLaser wall time. Memory: "
      "ru_maxrss before parsing and at the end, and VmHWM.\nFloor: read() through a 1 MiB "
      "buffer, then the same with std::from_chars on every number (min of 3, in this process).\n",
      config.self_path.c_str());
  nlohmann::json out;
  const fs::path dir = fs::temp_directory_path() / ("calib_bench_" + std::to_string(getpid()));
  fs::create_directories(dir);
  const EndToEndOptions e2e = MakeEndToEndOptions(config, dir);
  out["end_to_end_reps"] = reps;
  out["calib_cli"] = e2e.calib_cli;
  out["calib_args"] = e2e.calib_args;
  out["peer_solver"] = e2e.peer_solver;
  out["peer_args"] = e2e.peer_args;
  EndToEndReport report;
  out["real"] = RunSpeedRealSets(config, e2e, reps, &report);
  TextTable table({"N", "file MB", "read s", "from_chars s", "parse s", "parse/floor",
                   "closed form s", "refine s", "covariance s", "total s", "iters", "RSS before MB",
                   "RSS after MB", "VmHWM MB"});
  std::vector<double> ns, totals, e2e_ns, calib_walls, peer_ns, peer_walls;
  SizeFootprint last;
  for (int64_t n : sizes) {
    std::string peer_skip;
    const std::string skip = MemoryCheck(n, last, dir, &peer_skip);
    if (!skip.empty()) {
      std::printf("N=%lld skipped: %s\n", static_cast<long long>(n), skip.c_str());
      out["skipped"].push_back({{"intervals", n}, {"reason", skip}});
      continue;
    }
    LaserSimOptions sim;
    sim.num_intervals = static_cast<int>(n);
    sim.speed_time_constant_s = 0.0;
    const fs::path file = dir / ("sim_" + std::to_string(n) + ".tuple");
    const Stopwatch sim_watch;
    const long rss_before_sim = SelfRssKb();
    {
      LaserLog log = SimulateLaserLog(sim);
      log.has_timestamps = false;  // The authors' keys only, as in their files: peers read it too.
      const Status written = WriteLaserTuples(log, file.string());
      if (!written.ok()) {
        std::printf("N=%lld: cannot write the log: %s\n", static_cast<long long>(n),
                    written.message().c_str());
        continue;
      }
    }
    const long simulate_kb = std::max(0L, SelfRssKb() - rss_before_sim);
    const double sim_s = sim_watch.Seconds();
    const double file_mb = static_cast<double>(fs::file_size(file)) / (1024 * 1024);
    const ReadFloor floor = MeasureReadFloor(file.string(), 3);
    const StatusOr<nlohmann::json> child =
        RunChild("'" + config.self_path + "' --speed_child=" + std::to_string(n) +
                 " --speed_file='" + file.string() + "'");
    nlohmann::json run =
        child.ok() ? *child : nlohmann::json{{"intervals", n}, {"error", child.message()}};
    run["simulate_and_write_s"] = sim_s;
    run["file_mb"] = file_mb;
    run["floor_read_s"] = floor.read_s;
    run["floor_parse_s"] = floor.parse_s;
    run["floor_numbers"] = floor.numbers;
    if (!e2e.calib_cli.empty()) {
      run["end_to_end"] = RunEndToEnd(e2e, "N=" + std::to_string(n), file.string(),
                                      RepsFor(n, reps), peer_skip, &report);
    }
    fs::remove(file);
    if (!child.ok()) {
      std::printf("N=%lld: %s\n", static_cast<long long>(n), child.message().c_str());
      out["runs"].push_back(run);
      continue;
    }
    run["parse_over_floor"] = run["parse_s"].get<double>() / floor.parse_s;
    const auto mb = [&](const char* key) { return Format("%.1f", run[key].get<double>() / 1024); };
    table.AddRow({std::to_string(n), Format("%.1f", file_mb), Format("%.4f", floor.read_s),
                  Format("%.4f", floor.parse_s), Format("%.4f", run["parse_s"].get<double>()),
                  Format("%.1f", run["parse_over_floor"].get<double>()),
                  Format("%.3f", run["closed_form_s"].get<double>()),
                  Format("%.3f", run["refinement_s"].get<double>()),
                  Format("%.3f", run["covariance_s"].get<double>()),
                  Format("%.3f", run["total_s"].get<double>()),
                  std::to_string(run["iterations"].get<int>()), mb("maxrss_before_kb"),
                  mb("maxrss_after_kb"), mb("vmhwm_kb")});
    ns.push_back(static_cast<double>(n));
    totals.push_back(run["total_s"].get<double>());
    last = {
        n,
        std::max(run["vmhwm_kb"].get<long>(), SummaryMin(run["end_to_end"], "calib", "maxrss_kb")),
        SummaryMin(run["end_to_end"], "peer", "maxrss_kb"), static_cast<long>(file_mb * 1024),
        simulate_kb};
    for (const auto& [program, xs, ys] :
         {std::tuple{"calib", &e2e_ns, &calib_walls}, std::tuple{"peer", &peer_ns, &peer_walls}}) {
      const nlohmann::json& e = run["end_to_end"];
      if (!e.is_object() || !e.contains(program) || e[program]["summary"].is_null()) continue;
      xs->push_back(static_cast<double>(n));
      ys->push_back(e[program]["summary"]["wall_s"]["min"].get<double>());
    }
    out["runs"].push_back(run);
  }
  fs::remove_all(dir);
  table.Print();
  if (ns.size() >= 2) {
    const double slope = LogLogSlope(ns, totals);
    std::printf("Slope of log(total time) against log(N), least squares over %zu sizes: %.3f\n",
                ns.size(), slope);
    out["log_log_slope_total"] = slope;
  }
  if (!e2e.calib_cli.empty()) {
    std::printf(
        "\nEnd to end, each run a child process (fork/exec + wait4 from a fresh launcher), %d "
        "rounds interleaved calib, peer, calib, ... (%d at 10^6, 1 at 10^7); min and median of "
        "the successful runs.\ncalib: %s %s\npeer:  %s\n",
        reps, std::min(reps, 3), e2e.calib_cli.c_str(), e2e.calib_args.c_str(),
        e2e.peer_solver.empty() ? "(none: --peer_solver PATH)"
                                : (e2e.peer_solver + " " + e2e.peer_args).c_str());
    report.Print();
    for (const auto& [name, xs, ys] :
         {std::tuple{"calib", &e2e_ns, &calib_walls}, std::tuple{"peer", &peer_ns, &peer_walls}}) {
      if (xs->size() < 2) continue;
      const double slope = LogLogSlope(*xs, *ys);
      std::printf("Slope of log(%s wall min) against log(N) over %zu sizes: %.3f\n", name,
                  xs->size(), slope);
      out[std::string("log_log_slope_end_to_end_") + name] = slope;
    }
  }
  if (!config.quick) {
    out["micro"] = RunMicroBenchmarks();
  } else {
    std::printf("(Google Benchmark micro-benchmarks run only without --quick)\n");
  }
  return out;
}

}  // namespace calib::bench
