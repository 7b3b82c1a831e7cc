#ifndef CALIB_BENCHMARKS_BENCH_SPEED_SIZES_H_
#define CALIB_BENCHMARKS_BENCH_SPEED_SIZES_H_

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "benchmarks/bench_common.h"
#include "benchmarks/bench_end_to_end.h"

// Section speed on simulated logs, one size at a time: the file written, its read/parse floor,
// calib in process (stages, memory; a --speed_child) and end to end beside the peer.
namespace calib::bench {

class SpeedSizes {
 public:
  // Files go to `dir`; end-to-end rows to `report` (none when e2e.calib_cli is empty).
  SpeedSizes(const BenchConfig& config, const EndToEndOptions& e2e, int reps,
             std::filesystem::path dir, EndToEndReport* report);

  // Appends to out["runs"], or to out["skipped"] when the size would not fit in memory (judged
  // from the previous size) or on disk.
  void Run(int64_t n, nlohmann::json* out);

  // The in-process table and the log-log slope of its total; the end-to-end slopes into `out`.
  void PrintTable(nlohmann::json* out) const;
  void PrintEndToEndSlopes(nlohmann::json* out) const;

 private:
  // What the previous size used, to tell whether ten times as many intervals fit.
  struct Footprint {
    int64_t n = 0;
    long calib_kb = 0;  // The larger of the speed child's VmHWM and calib's ru_maxrss.
    long peer_kb = 0;
    long file_kb = 0;
    long simulate_kb = 0;  // This process's RSS growth while simulating and writing.
  };
  std::string MemoryCheck(int64_t n, std::string* peer_reason) const;
  void AddRow(int64_t n, const nlohmann::json& run);

  const BenchConfig& config_;
  const EndToEndOptions& e2e_;
  int reps_;
  std::filesystem::path dir_;
  EndToEndReport* report_;
  TextTable table_;
  Footprint last_;
  std::vector<double> ns_, totals_;
  std::vector<double> e2e_ns_[2], e2e_walls_[2];  // calib, peer
};

// The timing-aware calibration end to end on raw streams (odometry.csv and sensor_poses.csv; the
// simulator's default robot, seed 1, 5 % slips, pick-up stamps scattered by 2 ms, as `calib
// simulate --format stream --outliers 0.05 --logger_jitter 0.002`) of 10³, 10⁴ and, without
// --quick, 10⁵ intervals; calib alone. Rows go to `report`.
nlohmann::json RunSpeedStreams(const BenchConfig& config, const EndToEndOptions& e2e, int reps,
                               const std::filesystem::path& dir, EndToEndReport* report);

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_SPEED_SIZES_H_
