// The scan CSV reader (wide and long layouts).
#include <calib/core/scan/scan_csv.h>

#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto scans = calib::ParseScanCsv(calib::fuzz::AsText(data, size), "fuzz_scans.csv");
  calib::fuzz::Note(scans);
  return 0;
}
