#include <bzlib.h>
#include <calib/core/bz2_decompress.h>

#include <algorithm>
#include <memory>

namespace calib {
namespace {

// The output grows as the decompressor fills it, up to the bound, so that a bound far above what
// the data decompress to costs no memory.
void Grow(std::string* out, size_t used, size_t max_bytes) {
  const size_t next = std::max<size_t>(used * 2, size_t{1} << 16);
  out->resize(std::min(next, max_bytes));
}

// One stream from *data on, appended to *out (`used` bytes of it filled); *data advances past it.
Status DecompressStream(std::string_view* data, size_t max_bytes, std::string* out, size_t* used,
                        bool* ended) {
  bz_stream stream{};
  if (BZ2_bzDecompressInit(&stream, 0, 0) != BZ_OK) return Status::Internal("bz2: cannot init");
  std::unique_ptr<bz_stream, int (*)(bz_stream*)> guard(&stream, BZ2_bzDecompressEnd);
  stream.next_in = const_cast<char*>(data->data());
  stream.avail_in = static_cast<unsigned>(data->size());
  *ended = false;
  while (true) {
    if (*used == out->size()) {
      if (*used == max_bytes) break;
      Grow(out, *used, max_bytes);
    }
    stream.next_out = out->data() + *used;
    stream.avail_out = static_cast<unsigned>(std::min<size_t>(out->size() - *used, 1u << 30));
    const unsigned before_out = stream.avail_out;
    const int ret = BZ2_bzDecompress(&stream);
    *used += before_out - stream.avail_out;
    if (ret == BZ_STREAM_END) {
      *ended = true;
      break;
    }
    if (ret != BZ_OK) {
      return Status::InvalidInput("bz2 data are corrupt (libbz2 error " + std::to_string(ret) +
                                  ")");
    }
    if (stream.avail_in == 0 && stream.avail_out != 0) {
      return Status::InvalidInput("bz2 data end before their stream does (truncated)");
    }
  }
  data->remove_prefix(data->size() - stream.avail_in);
  return Status::Ok();
}

}  // namespace

Status Bz2Decompress(std::string_view data, const Bz2Options& options, std::string* out,
                     bool* ended) {
  if (data.size() > (size_t{1} << 31)) {
    return Status::InvalidInput("bz2 data of " + std::to_string(data.size()) +
                                " bytes: more than calib reads (2 GiB)");
  }
  out->clear();
  size_t used = 0;
  bool stream_ended = false;
  do {
    CALIB_RETURN_IF_ERROR(DecompressStream(&data, options.max_bytes, out, &used, &stream_ended));
  } while (options.concatenated && stream_ended && used < options.max_bytes && !data.empty());
  out->resize(used);
  if (ended != nullptr) *ended = stream_ended;
  return Status::Ok();
}

}  // namespace calib
