#include <calib/core/laser/laser_log_io.h>

#include <algorithm>
#include <filesystem>

#include "benchmarks/bench_end_to_end.h"
#include "benchmarks/bench_floor.h"

namespace calib::bench {

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
  return out;
}

}  // namespace calib::bench
