// The raw-stream reader: odometry.csv and sensor_poses.csv, cut at kFuzzSeparator.
#include <calib/core/laser/laser_log_io.h>

#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto files = calib::fuzz::SplitFuzzInput(data, size, 2);
  const auto log = calib::ParseLaserStream(files[0], files[1], "fuzz_stream");
  if (log.ok() && log->intervals.empty()) __builtin_trap();  // A log holds an interval.
  calib::fuzz::Note(log);
  return 0;
}
