#ifndef CALIB_CORE_BZ2_DECOMPRESS_H_
#define CALIB_CORE_BZ2_DECOMPRESS_H_

#include <calib/core/status.h>

#include <cstddef>
#include <string>
#include <string_view>

// bz2 decompression (Debian's libbz2), shared by the ROS 1 bag's chunks and .bz2 log files.
namespace calib {

struct Bz2Options {
  size_t max_bytes = 0;  // Stop once the output holds this much (the caller's bound).
  // A file that bzip2 (or pbzip2) wrote may hold several streams one after another; a bag's chunk
  // holds one.
  bool concatenated = false;
};

// Decompresses `data` into *out. Stopping at max_bytes is no error; *ended (when given) says
// whether the data's (last) stream ended. Errors: corrupt data, data that end before their
// stream does (truncated).
Status Bz2Decompress(std::string_view data, const Bz2Options& options, std::string* out,
                     bool* ended = nullptr);

}  // namespace calib

#endif  // CALIB_CORE_BZ2_DECOMPRESS_H_
