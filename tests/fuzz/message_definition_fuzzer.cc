// Any message through its definition (core/bag/message_definition.h), as a bag's raw topic is
// read: the input is a type name, the definition text and a message, cut at "=====" lines; the
// definition is parsed for both wire formats and every numeric field read.
#include <calib/core/bag/message_definition.h>

#include <string>

#include "tests/fuzz/fuzz_input.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto pieces = calib::fuzz::SplitFuzzInput(data, size, 3);
  const std::string type(pieces[0]), text(pieces[1]);
  const auto* message = reinterpret_cast<const uint8_t*>(pieces[2].data());
  for (const calib::WireFormat format : {calib::WireFormat::kRos1, calib::WireFormat::kCdr}) {
    const auto definition = calib::MessageDefinition::Parse(type, text, format);
    calib::fuzz::Note(definition);
    if (!definition.ok()) continue;
    const auto values =
        definition->ReadNumbers(message, pieces[2].size(), definition->NumericFields());
    calib::fuzz::Note(values);
  }
  return 0;
}
