// Read then calibrate, as `calib calibrate` does for a tuple or CSV log: the reader, the input
// checks and the laser calibration with default options, on at most kMaxIntervals intervals. Each
// must return a Status whatever the numbers.
#include <calib/core/laser/laser_log_io.h>
#include <calib/solvers/laser/calibrate_laser.h>
#include <calib/solvers/laser/laser_input_checks.h>

#include "tests/fuzz/fuzz_input.h"

namespace {
constexpr size_t kMaxIntervals = 200;
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  auto log = calib::ParseLaserLog(calib::fuzz::AsText(data, size), "fuzz_log");
  calib::fuzz::Note(log);
  if (!log.ok()) return 0;
  if (log->intervals.size() > kMaxIntervals) return 0;  // Keeps each run short.
  const calib::Status checked = calib::CheckLaserInput(*log);
  // The library must not abort even on input the checks refuse.
  const auto result = calib::CalibrateLaser(log->intervals);
  calib::fuzz::Note(checked);
  calib::fuzz::Note(result);
  return 0;
}
