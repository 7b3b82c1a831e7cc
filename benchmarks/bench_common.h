#ifndef CALIB_BENCHMARKS_BENCH_COMMON_H_
#define CALIB_BENCHMARKS_BENCH_COMMON_H_

#include <calib/core/laser/laser_params.h>
#include <calib/core/text_format.h>

#include <Eigen/Core>
#include <chrono>
#include <cstdio>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

// Shared pieces of calib_bench: run settings, timing, a parallel loop and plain-text tables
// (text through calib::Format of core/text_format.h).
namespace calib::bench {

struct BenchConfig {
  bool quick = false;
  int seeds = 0;  // Seeds per scenario; 0: the mode's default.
  int threads = 2;
  std::string censi_dir;
  std::string self_path;  // This binary, re-executed for per-process memory peaks.
  // Section speed: `calib calibrate` end to end, beside a peer solver when one is given.
  std::string calib_cli;    // Empty: `calib` next to this binary.
  std::string calib_args;   // Pattern with {input} and {output}.
  std::string peer_solver;  // Empty: calib alone.
  std::string peer_args;
  int speed_reps = 0;  // Interleaved rounds; 0: 7 (3 with quick).
};

class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()) {}
  double Seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::chrono::steady_clock::time_point start_;
};

// Calls f(0) … f(n − 1) on `threads` workers; f must be safe to run concurrently.
void ParallelFor(int n, int threads, const std::function<void(int)>& f);

double Median(std::vector<double> values);

// Least-squares slope of log(y) against log(x): the exponent of a power-law scaling.
double LogLogSlope(const std::vector<double>& x, const std::vector<double>& y);

// Parameter i of a LaserParamVector in display units: mm for lengths, mrad (or deg) for θ.
double ToDisplay(int param, double value, bool degrees = false);

// estimate − truth with θ wrapped.
LaserParamVector LaserError(const LaserCalibration& estimate, const LaserCalibration& truth);

nlohmann::json ToJson(const LaserParamVector& v);
nlohmann::json ToJson(const Eigen::Vector3d& v);

// Columns right-aligned except the first; a row of a single "-" cell draws a rule.
class TextTable {
 public:
  explicit TextTable(std::vector<std::string> header) : header_(std::move(header)) {}
  void AddRow(std::vector<std::string> cells) { rows_.push_back(std::move(cells)); }
  void AddRule() { rows_.push_back({"-"}); }
  void Print(std::FILE* out = stdout) const;

 private:
  std::vector<std::string> header_;
  std::vector<std::vector<std::string>> rows_;
};

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_COMMON_H_
