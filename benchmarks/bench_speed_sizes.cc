#include "benchmarks/bench_speed_sizes.h"

#include <calib/core/laser/laser_log_io.h>
#include <calib/core/laser/laser_simulator.h>

#include <algorithm>
#include <cmath>

#include "benchmarks/bench_floor.h"
#include "benchmarks/bench_process.h"

namespace calib::bench {
namespace {

namespace fs = std::filesystem;

const char* const kPrograms[2] = {"calib", "peer"};

// Rounds per size: fewer where one run takes long.
int RepsFor(int64_t n, int reps) {
  if (n <= 100000) return reps;
  return n <= 1000000 ? std::min(reps, 3) : 1;
}

// The successful runs' minimum of `key`; 0 without any.
double SummaryMin(const nlohmann::json& e2e, const char* program, const char* key) {
  if (!e2e.is_object() || !e2e.contains(program) || e2e[program]["summary"].is_null()) return 0;
  return e2e[program]["summary"][key]["min"].get<double>();
}

}  // namespace

SpeedSizes::SpeedSizes(const BenchConfig& config, const EndToEndOptions& e2e, int reps,
                       fs::path dir, EndToEndReport* report)
    : config_(config),
      e2e_(e2e),
      reps_(reps),
      dir_(std::move(dir)),
      report_(report),
      table_({"N", "file MB", "read s", "from_chars s", "parse s", "parse/floor", "closed form s",
              "refine s", "covariance s", "total s", "iters", "RSS before MB", "RSS after MB",
              "VmHWM MB"}) {}

std::string SpeedSizes::MemoryCheck(int64_t n, std::string* peer_reason) const {
  if (n <= 1000000 || last_.n == 0) return "";
  const double scale = static_cast<double>(n) / last_.n;
  const double file_bytes = scale * last_.file_kb * 1024.0;
  std::error_code error;
  const double disk = static_cast<double>(fs::space(dir_, error).available);
  if (!error && disk < 1.5 * file_bytes) {
    return Format("the file needs about %.1f GB, %.1f GB free on %s", file_bytes / 1e9, disk / 1e9,
                  dir_.c_str());
  }
  const long available = MemAvailableKb();
  if (available < 0) return "MemAvailable is unknown";
  const auto gb = [](double kb) { return kb * 1024 / 1e9; };
  const double calib_kb = scale * (last_.calib_kb + last_.simulate_kb + last_.file_kb);
  if (available < 1.25 * calib_kb) {
    return Format(
        "needs about %.1f GB (%gx the last size's peak, simulation and file), MemAvailable %.1f GB",
        gb(calib_kb), scale, gb(available));
  }
  const double peer_kb = scale * (last_.peer_kb + last_.simulate_kb + last_.file_kb);
  if (e2e_.peer_solver.empty()) return "";
  if (last_.peer_kb == 0) {
    *peer_reason = Format("no successful run at N=%lld to size its memory by",
                          static_cast<long long>(last_.n));
  } else if (available < 1.25 * peer_kb) {
    *peer_reason = Format("needs about %.1f GB (%gx its peak at N=%lld), MemAvailable %.1f GB",
                          gb(peer_kb), scale, static_cast<long long>(last_.n), gb(available));
  }
  return "";
}

void SpeedSizes::Run(int64_t n, nlohmann::json* out) {
  std::string peer_skip;
  const std::string skip = MemoryCheck(n, &peer_skip);
  if (!skip.empty()) {
    std::printf("N=%lld skipped: %s\n", static_cast<long long>(n), skip.c_str());
    (*out)["skipped"].push_back({{"intervals", n}, {"reason", skip}});
    return;
  }
  LaserSimOptions sim;
  sim.num_intervals = static_cast<int>(n);
  sim.speed_time_constant_s = 0.0;
  const fs::path file = dir_ / ("sim_" + std::to_string(n) + ".tuple");
  const Stopwatch sim_watch;
  const long rss_before_sim = SelfRssKb();
  {
    LaserLog log = SimulateLaserLog(sim);
    log.has_timestamps = false;  // The authors' keys only, as in their files: peers read it too.
    const Status written = WriteLaserTuples(log, file.string());
    if (!written.ok()) {
      std::printf("N=%lld: cannot write the log: %s\n", static_cast<long long>(n),
                  written.message().c_str());
      return;
    }
  }
  const long simulate_kb = std::max(0L, SelfRssKb() - rss_before_sim);
  const double sim_s = sim_watch.Seconds();
  const double file_mb = static_cast<double>(fs::file_size(file)) / (1024 * 1024);
  const ReadFloor floor = MeasureReadFloor(file.string(), 3);
  const StatusOr<nlohmann::json> child =
      RunJsonChild("'" + config_.self_path + "' --speed_child=" + std::to_string(n) +
                   " --speed_file='" + file.string() + "'");
  nlohmann::json run =
      child.ok() ? *child : nlohmann::json{{"intervals", n}, {"error", child.message()}};
  run["simulate_and_write_s"] = sim_s;
  run["file_mb"] = file_mb;
  run["floor_read_s"] = floor.read_s;
  run["floor_parse_s"] = floor.parse_s;
  run["floor_numbers"] = floor.numbers;
  if (!e2e_.calib_cli.empty()) {
    run["end_to_end"] = RunEndToEnd(e2e_, "N=" + std::to_string(n), file.string(),
                                    RepsFor(n, reps_), peer_skip, report_);
  }
  fs::remove(file);
  if (!child.ok()) {
    std::printf("N=%lld: %s\n", static_cast<long long>(n), child.message().c_str());
    (*out)["runs"].push_back(run);
    return;
  }
  run["parse_over_floor"] = run["parse_s"].get<double>() / floor.parse_s;
  AddRow(n, run);
  const nlohmann::json& e2e = run["end_to_end"];
  last_ = {n,
           std::max(run["vmhwm_kb"].get<long>(),
                    static_cast<long>(SummaryMin(e2e, "calib", "maxrss_kb"))),
           static_cast<long>(SummaryMin(e2e, "peer", "maxrss_kb")),
           static_cast<long>(file_mb * 1024), simulate_kb};
  for (int p = 0; p < 2; ++p) {
    const double wall = SummaryMin(e2e, kPrograms[p], "wall_s");
    if (wall <= 0) continue;
    e2e_ns_[p].push_back(static_cast<double>(n));
    e2e_walls_[p].push_back(wall);
  }
  (*out)["runs"].push_back(run);
}

void SpeedSizes::AddRow(int64_t n, const nlohmann::json& run) {
  const auto get = [&](const char* key) { return run[key].get<double>(); };
  const auto mb = [&](const char* key) { return Format("%.1f", get(key) / 1024); };
  table_.AddRow({std::to_string(n), Format("%.1f", get("file_mb")),
                 Format("%.4f", get("floor_read_s")), Format("%.4f", get("floor_parse_s")),
                 Format("%.4f", get("parse_s")), Format("%.1f", get("parse_over_floor")),
                 Format("%.3f", get("closed_form_s")), Format("%.3f", get("refinement_s")),
                 Format("%.3f", get("covariance_s")), Format("%.3f", get("total_s")),
                 std::to_string(run["iterations"].get<int>()), mb("maxrss_before_kb"),
                 mb("maxrss_after_kb"), mb("vmhwm_kb")});
  ns_.push_back(static_cast<double>(n));
  totals_.push_back(get("total_s"));
}

void SpeedSizes::PrintTable(nlohmann::json* out) const {
  table_.Print();
  if (ns_.size() < 2) return;
  const double slope = LogLogSlope(ns_, totals_);
  std::printf("Slope of log(total time) against log(N), least squares over %zu sizes: %.3f\n",
              ns_.size(), slope);
  (*out)["log_log_slope_total"] = slope;
}

void SpeedSizes::PrintEndToEndSlopes(nlohmann::json* out) const {
  for (int p = 0; p < 2; ++p) {
    if (e2e_ns_[p].size() < 2) continue;
    const std::vector<double>& ns = e2e_ns_[p];
    const std::vector<double>& walls = e2e_walls_[p];
    const double slope = LogLogSlope(ns, walls);
    // Start-up dominates the small sizes; the largest two show the growth itself.
    const size_t k = ns.size();
    const double top = std::log(walls[k - 1] / walls[k - 2]) / std::log(ns[k - 1] / ns[k - 2]);
    std::printf(
        "Slope of log(%s wall min) against log(N): %.3f over %zu sizes, %.3f between the largest "
        "two\n",
        kPrograms[p], slope, k, top);
    (*out)[std::string("log_log_slope_end_to_end_") + kPrograms[p]] = slope;
    (*out)[std::string("log_log_slope_end_to_end_") + kPrograms[p] + "_largest_two"] = top;
  }
}

}  // namespace calib::bench
