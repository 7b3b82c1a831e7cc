// The ROS 2 bag reader of rosbag2's sqlite3 storage (.db3), over a database's bytes.
#include <calib/core/bag/robot_messages.h>

#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto messages = calib::ReadSqliteBytes(calib::fuzz::AsText(data, size), "fuzz.db3");
  calib::fuzz::Note(messages);
  return 0;
}
