#include <calib/core/laser/laser_log_io.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/laser/laser_input_checks.h>
#include <calib/solvers/laser/laser_model_screen.h>

#include <algorithm>
#include <filesystem>
#include <limits>

#include "benchmarks/bench_end_to_end.h"
#include "benchmarks/bench_floor.h"

namespace calib::bench {
namespace {

// The stages of `calib calibrate` on a tuple log, run one after another in this process (min of
// `runs` each): where its CPU time goes, without the overlap of the model screen's thread. The
// base fit is CalibrateLaserJoint without the interval-jitter treatment, given the checks'
// consensus screen as the command gives it; the jitter is the difference with the treatment on.
nlohmann::json MeasureStages(const std::string& path, int runs, const char* name,
                             TextTable* table) {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  double read_s = kNone, checks_s = kNone, base_s = kNone, jitter_s = kNone, screen_s = kNone;
  for (int run = 0; run < runs; ++run) {
    const Stopwatch read_watch;
    const StatusOr<LaserLog> log = ReadLaserLog(path);
    read_s = std::min(read_s, read_watch.Seconds());
    std::shared_ptr<const ConsensusScreen> consensus;
    LaserInputCheckOptions checks;
    checks.consensus_screen = &consensus;
    const Stopwatch checks_watch;
    if (!log.ok() || !CheckLaserInput(*log, checks).ok()) return {};
    checks_s = std::min(checks_s, checks_watch.Seconds());
    LaserCalibrationOptions options;
    options.consensus_screen = consensus;
    options.interval_jitter = false;
    const Stopwatch base_watch;
    if (!CalibrateLaserJoint({&log->intervals}, options).ok()) return {};
    const double base = base_watch.Seconds();
    options.interval_jitter = true;
    const Stopwatch jitter_watch;
    if (!CalibrateLaserJoint({&log->intervals}, options).ok()) return {};
    base_s = std::min(base_s, base);
    jitter_s = std::min(jitter_s, jitter_watch.Seconds() - base);
    const Stopwatch screen_watch;
    if (!ScreenLaserModel(log->intervals, LaserCalibrationOptions{}, false).ok()) return {};
    screen_s = std::min(screen_s, screen_watch.Seconds());
  }
  const double sum_s = read_s + checks_s + base_s + jitter_s + screen_s;
  table->AddRow({name, Format("%.1f", 1e3 * read_s), Format("%.1f", 1e3 * checks_s),
                 Format("%.1f", 1e3 * base_s), Format("%.1f", 1e3 * jitter_s),
                 Format("%.1f", 1e3 * screen_s), Format("%.1f", 1e3 * sum_s)});
  return {{"read_s", read_s},     {"checks_s", checks_s}, {"base_fit_s", base_s},
          {"jitter_s", jitter_s}, {"screen_s", screen_s}, {"sum_s", sum_s}};
}

}  // namespace

nlohmann::json RunSpeedRealSets(const BenchConfig& config, const EndToEndOptions& options, int reps,
                                EndToEndReport* report) {
  namespace fs = std::filesystem;
  nlohmann::json out = nlohmann::json::array();
  if (!fs::is_directory(config.censi_dir)) {
    std::printf("Real sets skipped: %s is not a folder (--censi_dir).\n", config.censi_dir.c_str());
    return out;
  }
  constexpr int kFloorRuns = 5;
  TextTable table(
      {"set", "intervals", "file MB", "read s", "from_chars s", "parse s", "parse/floor"});
  TextTable stages(
      {"set", "read ms", "checks ms", "base fit ms", "jitter ms", "model screen ms", "sum ms"});
  for (const char* name : {"l90", "lmov", "lstraight"}) {
    const std::string path = (fs::path(config.censi_dir) / (std::string(name) + ".tuple")).string();
    const ReadFloor floor = MeasureReadFloor(path, kFloorRuns);
    double parse_s = -1;
    int64_t intervals = 0;
    for (int run = 0; run < kFloorRuns; ++run) {
      const Stopwatch watch;
      const StatusOr<LaserLog> log = ReadLaserLog(path);
      const double s = watch.Seconds();
      if (!log.ok()) {
        std::printf("%s: cannot read: %s\n", name, log.message().c_str());
        break;
      }
      intervals = static_cast<int64_t>(log->intervals.size());
      parse_s = parse_s < 0 ? s : std::min(parse_s, s);
    }
    if (!floor.ok() || parse_s < 0) continue;
    nlohmann::json set = {{"set", name},
                          {"intervals", intervals},
                          {"file_bytes", floor.bytes},
                          {"floor_read_s", floor.read_s},
                          {"floor_parse_s", floor.parse_s},
                          {"floor_numbers", floor.numbers},
                          {"parse_s", parse_s},
                          {"parse_over_floor", parse_s / floor.parse_s}};
    table.AddRow({name, std::to_string(intervals), Format("%.2f", floor.bytes / 1048576.0),
                  Format("%.5f", floor.read_s), Format("%.5f", floor.parse_s),
                  Format("%.5f", parse_s), Format("%.1f", parse_s / floor.parse_s)});
    set["stages"] = MeasureStages(path, kFloorRuns, name, &stages);
    if (!options.calib_cli.empty()) {
      set["end_to_end"] = RunEndToEnd(options, name, path, reps, "", report);
    }
    out.push_back(set);
  }
  std::printf(
      "Real sets (%s): the floor (min of %d, page cache warm) against ReadLaserLog in process "
      "(min of %d):\n",
      config.censi_dir.c_str(), kFloorRuns, kFloorRuns);
  table.Print();
  std::printf(
      "The stages of `calib calibrate` one after another in this process (min of %d; the command "
      "runs the model screen on a second thread beside the rest, after reading):\n",
      kFloorRuns);
  stages.Print();
  return out;
}

}  // namespace calib::bench
