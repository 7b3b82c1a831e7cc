#include <calib/core/text_format.h>

#include <cstdarg>
#include <cstdio>

namespace calib {

std::string Format(const char* format, ...) {
  va_list args;
  va_start(args, format);
  char buffer[512];
  std::vsnprintf(buffer, sizeof(buffer), format, args);
  va_end(args);
  return buffer;
}

}  // namespace calib
