#ifndef CALIB_CORE_BZ2_DECOMPRESS_H_
#define CALIB_CORE_BZ2_DECOMPRESS_H_

#include <calib/core/status.h>

#include <cstddef>
#include <functional>
#include <memory>
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

// The same piece by piece, so that a long log is never held whole. `data` must outlive it.
class Bz2Stream {
 public:
  Bz2Stream(std::string_view data, bool concatenated);
  ~Bz2Stream();
  Bz2Stream(const Bz2Stream&) = delete;
  Bz2Stream& operator=(const Bz2Stream&) = delete;

  // Appends up to max_bytes more of the output to *out; none once the data are used up.
  Status Append(size_t max_bytes, std::string* out);
  // Whether the (last) stream has ended.
  bool ended() const { return ended_; }

 private:
  struct Decoder;  // libbz2's state for the stream under way.

  std::string_view data_;
  bool concatenated_;
  std::unique_ptr<Decoder> decoder_;
  bool ended_ = false;
};

// Decompresses a bzip2 file's `data` (streams one after another) in pieces of piece_bytes on a
// second thread, while `consume` reads the pieces in order on the calling thread. Stops at the
// first error, the consumer's or the data's (corrupt, truncated), and returns it.
Status ForEachBz2Piece(std::string_view data, size_t piece_bytes,
                       const std::function<Status(std::string_view piece)>& consume);

}  // namespace calib

#endif  // CALIB_CORE_BZ2_DECOMPRESS_H_
