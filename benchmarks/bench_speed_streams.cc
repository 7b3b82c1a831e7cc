#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>
#include <calib/core/timing/logging_model.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "benchmarks/bench_speed_sizes.h"

namespace calib::bench {

nlohmann::json RunSpeedStreams(const BenchConfig& config, const EndToEndOptions& e2e, int reps,
                               const std::filesystem::path& dir, EndToEndReport* report) {
  nlohmann::json out = nlohmann::json::array();
  if (e2e.calib_cli.empty()) return out;
  std::vector<int> sizes = {1000, 10000};
  if (!config.quick) sizes.push_back(100000);
  for (const int n : sizes) {
    LaserSimOptions options;
    options.num_intervals = n;
    options.seed = 1;
    options.outlier_fraction = 0.05;
    LoggingModel logging;
    logging.logger_jitter_s = 0.002;
    const LaserStreams streams = SimulateLoggedLaserStreams(options, logging);
    const std::filesystem::path path = dir / ("streams_" + std::to_string(n));
    const Status written = WriteLaserStream(streams.odometry, streams.sensor_poses, path.string());
    if (!written.ok()) {
      out.push_back({{"intervals", n}, {"error", written.message()}});
      continue;
    }
    nlohmann::json run = RunEndToEnd(
        e2e, "streams " + std::to_string(n), path.string(), n >= 100000 ? std::min(reps, 2) : reps,
        "the authors' solver takes intervals, not raw streams", report);
    run["intervals"] = n;
    out.push_back(std::move(run));
  }
  return out;
}

}  // namespace calib::bench
