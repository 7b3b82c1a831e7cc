#ifndef CALIB_TESTS_FUZZ_FUZZ_INPUT_H_
#define CALIB_TESTS_FUZZ_FUZZ_INPUT_H_

#include <calib/core/status.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string_view>
#include <vector>

// Pieces of one fuzz input for readers of several files (a stream directory, a bearing log): the
// input is cut at each kFuzzSeparator line, and missing pieces are empty.
namespace calib::fuzz {

inline constexpr std::string_view kFuzzSeparator = "\n=====\n";

inline std::vector<std::string_view> SplitFuzzInput(const uint8_t* data, size_t size,
                                                    size_t pieces) {
  std::string_view rest(reinterpret_cast<const char*>(data), size);
  std::vector<std::string_view> out;
  while (out.size() + 1 < pieces) {
    const size_t cut = rest.find(kFuzzSeparator);
    if (cut == std::string_view::npos) break;
    out.push_back(rest.substr(0, cut));
    rest.remove_prefix(cut + kFuzzSeparator.size());
  }
  out.push_back(rest);
  out.resize(pieces);
  return out;
}

inline std::string_view AsText(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// With CALIB_FUZZ_VERBOSE set, prints what the reader said (to check that seeds are accepted).
template <typename T>
void Note(const T& status) {
  static const bool verbose = std::getenv("CALIB_FUZZ_VERBOSE") != nullptr;
  if (verbose) std::fprintf(stderr, "  -> %s\n", status.ok() ? "ok" : status.message().c_str());
}

}  // namespace calib::fuzz

#endif  // CALIB_TESTS_FUZZ_FUZZ_INPUT_H_
