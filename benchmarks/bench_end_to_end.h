#ifndef CALIB_BENCHMARKS_BENCH_END_TO_END_H_
#define CALIB_BENCHMARKS_BENCH_END_TO_END_H_

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "benchmarks/bench_common.h"

// `calib calibrate` and, when given, a peer solver run end to end on the same file as child
// processes, interleaved (calib, peer, calib, peer, ...), so that both see the same machine load.
namespace calib::bench {

struct EndToEndOptions {
  std::string launcher;     // This binary (re-executed as a small launcher).
  std::string calib_cli;    // The `calib` binary; empty: no end-to-end runs.
  std::string calib_args;   // Argument pattern with {input} and {output}.
  std::string peer_solver;  // Empty: calib alone.
  std::string peer_args;
  std::string work_dir;  // Each program runs in its own folder under it.
};

// The rows of every input, and numbered notes (failures, skips) printed under them, so that a
// long message does not widen a column.
struct EndToEndReport {
  EndToEndReport();
  std::string AddNote(const std::string& note);  // Returns "[k]".
  void Print() const;
  TextTable table;
  std::vector<std::string> notes;
};

// `reps` interleaved rounds on `input`; the peer is left out (with `peer_skip_reason` in the
// report) when that is not empty. Adds rows to `report`; returns the runs, min and median of wall
// time, CPU time (user + sys), peak RSS and page faults per program, and the ratios calib/peer.
nlohmann::json RunEndToEnd(const EndToEndOptions& options, const std::string& label,
                           const std::string& input, int reps, const std::string& peer_skip_reason,
                           EndToEndReport* report);

// Part of section speed: on each published Censi et al. set, the read/parse floor against
// ReadLaserLog, and RunEndToEnd (unless options.calib_cli is empty).
nlohmann::json RunSpeedRealSets(const BenchConfig& config, const EndToEndOptions& options, int reps,
                                EndToEndReport* report);

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_END_TO_END_H_
