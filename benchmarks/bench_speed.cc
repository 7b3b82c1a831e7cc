#include <calib/core/laser/laser_log_io.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "benchmarks/bench_end_to_end.h"
#include "benchmarks/bench_sections.h"
#include "benchmarks/bench_speed_sizes.h"

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
  SpeedSizes sizes_run(config, e2e, reps, dir, &report);
  for (int64_t n : sizes) sizes_run.Run(n, &out);
  out["streams"] = RunSpeedStreams(config, e2e, reps, dir, &report);
  fs::remove_all(dir);
  sizes_run.PrintTable(&out);
  if (!e2e.calib_cli.empty()) {
    std::printf(
        "\nEnd to end, each run a child process (fork/exec + wait4 from a fresh launcher), %d "
        "rounds interleaved calib, peer, calib, ... (%d at 10^6, 1 at 10^7); min and median of "
        "the successful runs.\ncalib: %s %s\npeer:  %s\n",
        reps, std::min(reps, 3), e2e.calib_cli.c_str(), e2e.calib_args.c_str(),
        e2e.peer_solver.empty() ? "(none: --peer_solver PATH)"
                                : (e2e.peer_solver + " " + e2e.peer_args).c_str());
    report.Print();
    sizes_run.PrintEndToEndSlopes(&out);
  }
  if (!config.quick) {
    out["micro"] = RunMicroBenchmarks();
  } else {
    std::printf("(Google Benchmark micro-benchmarks run only without --quick)\n");
  }
  return out;
}

}  // namespace calib::bench
