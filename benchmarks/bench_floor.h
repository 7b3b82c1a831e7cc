#ifndef CALIB_BENCHMARKS_BENCH_FLOOR_H_
#define CALIB_BENCHMARKS_BENCH_FLOOR_H_

#include <cstdint>
#include <string>

// The floor under a reader: what streaming a file and converting its numbers cost with nothing
// else done, to set a parse time against.
namespace calib::bench {

struct ReadFloor {
  double read_s = -1;   // read() through a fixed 1 MiB buffer, min over the runs
  double parse_s = -1;  // the same plus std::from_chars on every number, min over the runs
  int64_t bytes = 0;
  int64_t numbers = 0;
  bool ok() const { return read_s >= 0; }
};

// In process, page cache warm (the first of `runs` warms it).
ReadFloor MeasureReadFloor(const std::string& path, int runs);

}  // namespace calib::bench

#endif  // CALIB_BENCHMARKS_BENCH_FLOOR_H_
