// The ROS 2 bag (MCAP) reader.
#include <calib/core/bag/robot_messages.h>

#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto messages = calib::ReadMcapBytes(calib::fuzz::AsText(data, size), "fuzz.mcap");
  calib::fuzz::Note(messages);
  return 0;
}
