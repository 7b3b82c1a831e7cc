// The ROS 1 bag reader.
#include <calib/core/bag/robot_messages.h>

#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto messages = calib::ReadRos1BagBytes(calib::fuzz::AsText(data, size), "fuzz.bag");
  calib::fuzz::Note(messages);
  return 0;
}
