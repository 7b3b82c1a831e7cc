// The bearing log reader: odometry.csv, bearings.csv and meta.json, cut at kFuzzSeparator.
#include <calib/core/bearing/bearing_log_io.h>

#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto files = calib::fuzz::SplitFuzzInput(data, size, 3);
  const auto log = calib::ParseBearingLog(files[0], files[1], files[2], "fuzz_bearing");
  // What the reader accepts, the validation of logs built in memory accepts too.
  if (log.ok() && !calib::ValidateBearingLog(*log).ok()) __builtin_trap();
  calib::fuzz::Note(log);
  return 0;
}
