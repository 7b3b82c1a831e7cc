#ifndef CALIB_CORE_TEXT_FORMAT_H_
#define CALIB_CORE_TEXT_FORMAT_H_

#include <string>

// printf into a std::string: the one formatter of the library's words, the report writers and
// calib_bench.
namespace calib {

// At most 511 characters (longer output is cut): one sentence, one line of a table, one SVG
// element.
std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));

}  // namespace calib

#endif  // CALIB_CORE_TEXT_FORMAT_H_
