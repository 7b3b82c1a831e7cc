// The laser CSV reader (with the drop of absurd intervals ReadLaserLog applies).
#include <calib/core/laser/laser_log_io.h>

#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto log =
      calib::ParseLaserLog(calib::fuzz::AsText(data, size), "fuzz.csv", calib::LaserFormat::kCsv);
  if (log.ok() && log->intervals.empty()) __builtin_trap();  // A log holds an interval.
  calib::fuzz::Note(log);
  return 0;
}
