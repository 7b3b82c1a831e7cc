#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

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

nlohmann::json RunSpeed(const BenchConfig& config) {
  std::printf("\n=== Section speed: wall time and peak memory against N ===\n");
  const std::vector<int64_t> sizes = config.quick
                                         ? std::vector<int64_t>{1000, 10000, 100000}
                                         : std::vector<int64_t>{1000, 10000, 100000, 1000000};
  std::printf(
      "Log: SimulateLaserLog seed 1 (rich trajectory, default noise, no outliers, "
      "speed_time_constant_s=0), written with WriteLaserTuples to a temp dir.\n"
      "Each N runs in a fresh child process (%s --speed_child=N): ReadLaserLog, then "
      "CalibrateLaser with defaults (Ceres 2 threads).\nStage times are "
      "CalibrateLaser's own; total = parse + CalibrateLaser wall time. Memory: "
      "ru_maxrss before parsing and at the end, and VmHWM.\n",
      config.self_path.c_str());
  nlohmann::json out;
  const fs::path dir = fs::temp_directory_path() / ("calib_bench_" + std::to_string(getpid()));
  fs::create_directories(dir);
  TextTable table({"N", "file MB", "parse s", "closed form s", "refine s", "covariance s",
                   "total s", "iters", "RSS before MB", "RSS after MB", "VmHWM MB"});
  std::vector<double> ns, totals;
  for (int64_t n : sizes) {
    LaserSimOptions sim;
    sim.num_intervals = static_cast<int>(n);
    sim.speed_time_constant_s = 0.0;
    const fs::path file = dir / ("sim_" + std::to_string(n) + ".tuple");
    const Stopwatch sim_watch;
    {
      const LaserLog log = SimulateLaserLog(sim);
      const Status written = WriteLaserTuples(log, file.string());
      if (!written.ok()) {
        std::printf("N=%lld: cannot write the log: %s\n", static_cast<long long>(n),
                    written.message().c_str());
        continue;
      }
    }
    const double sim_s = sim_watch.Seconds();
    const double file_mb = static_cast<double>(fs::file_size(file)) / (1024 * 1024);
    const StatusOr<nlohmann::json> child =
        RunChild("'" + config.self_path + "' --speed_child=" + std::to_string(n) +
                 " --speed_file='" + file.string() + "'");
    fs::remove(file);
    if (!child.ok()) {
      std::printf("N=%lld: %s\n", static_cast<long long>(n), child.message().c_str());
      out["runs"].push_back({{"intervals", n}, {"error", child.message()}});
      continue;
    }
    nlohmann::json run = *child;
    run["simulate_and_write_s"] = sim_s;
    run["file_mb"] = file_mb;
    const auto mb = [&](const char* key) { return Format("%.1f", run[key].get<double>() / 1024); };
    table.AddRow(
        {std::to_string(n), Format("%.1f", file_mb), Format("%.3f", run["parse_s"].get<double>()),
         Format("%.3f", run["closed_form_s"].get<double>()),
         Format("%.3f", run["refinement_s"].get<double>()),
         Format("%.3f", run["covariance_s"].get<double>()),
         Format("%.3f", run["total_s"].get<double>()), std::to_string(run["iterations"].get<int>()),
         mb("maxrss_before_kb"), mb("maxrss_after_kb"), mb("vmhwm_kb")});
    ns.push_back(static_cast<double>(n));
    totals.push_back(run["total_s"].get<double>());
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
  if (!config.quick) {
    out["micro"] = RunMicroBenchmarks();
  } else {
    std::printf("(Google Benchmark micro-benchmarks run only without --quick)\n");
  }
  return out;
}

}  // namespace calib::bench
