#include <bzlib.h>
#include <calib/core/bz2_decompress.h>

#include <algorithm>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <new>
#include <thread>
#include <utility>

namespace calib {

struct Bz2Stream::Decoder {
  bz_stream stream{};
  bool initialized = false;
  ~Decoder() {
    if (initialized) BZ2_bzDecompressEnd(&stream);
  }
};

Bz2Stream::Bz2Stream(std::string_view data, bool concatenated)
    : data_(data), concatenated_(concatenated) {}

Bz2Stream::~Bz2Stream() = default;

Status Bz2Stream::Append(size_t max_bytes, std::string* out) {
  const size_t limit = out->size() + max_bytes;
  size_t used = out->size();
  while (used < limit) {
    if (decoder_ == nullptr) {
      // After the first stream, only a bzip2 file's further streams follow.
      if (ended_ && (!concatenated_ || data_.empty())) break;
      auto decoder = std::make_unique<Decoder>();
      decoder->initialized = BZ2_bzDecompressInit(&decoder->stream, 0, 0) == BZ_OK;
      if (!decoder->initialized) return Status::Internal("bz2: cannot init");
      decoder->stream.next_in = const_cast<char*>(data_.data());
      decoder->stream.avail_in = static_cast<unsigned>(data_.size());
      decoder_ = std::move(decoder);
      ended_ = false;
    }
    bz_stream& stream = decoder_->stream;
    // The output grows as the decompressor fills it, so that a bound far above what the data
    // decompress to costs no memory.
    if (used == out->size()) out->resize(std::min(limit, std::max<size_t>(used * 2, 1 << 16)));
    stream.next_out = out->data() + used;
    stream.avail_out = static_cast<unsigned>(std::min<size_t>(out->size() - used, 1u << 30));
    const unsigned before_out = stream.avail_out;
    const int ret = BZ2_bzDecompress(&stream);
    used += before_out - stream.avail_out;
    if (ret == BZ_STREAM_END) {
      data_.remove_prefix(data_.size() - stream.avail_in);
      decoder_.reset();
      ended_ = true;
      continue;
    }
    if (ret != BZ_OK) {
      out->resize(used);
      return Status::InvalidInput("bz2 data are corrupt (libbz2 error " + std::to_string(ret) +
                                  ")");
    }
    if (stream.avail_in == 0 && stream.avail_out != 0) {
      out->resize(used);
      return Status::InvalidInput("bz2 data end before their stream does (truncated)");
    }
  }
  out->resize(used);
  return Status::Ok();
}

Status Bz2Decompress(std::string_view data, const Bz2Options& options, std::string* out,
                     bool* ended) {
  if (data.size() > (size_t{1} << 31)) {
    return Status::InvalidInput("bz2 data of " + std::to_string(data.size()) +
                                " bytes: more than calib reads (2 GiB)");
  }
  out->clear();
  Bz2Stream stream(data, options.concatenated);
  CALIB_RETURN_IF_ERROR(stream.Append(options.max_bytes, out));
  if (ended != nullptr) *ended = stream.ended();
  return Status::Ok();
}

namespace {

// The pieces decompressed ahead of the consumer (two at most), and how the producer ended.
struct PieceQueue {
  std::mutex mutex;
  std::condition_variable changed;
  std::deque<std::string> pieces;
  Status status = Status::Ok();
  bool done = false, stop = false;
};

void Produce(std::string_view data, size_t piece_bytes, PieceQueue* queue) {
  Status status = Status::Ok();
  try {
    Bz2Stream stream(data, true);
    while (true) {
      std::string piece;
      status = stream.Append(piece_bytes, &piece);
      if (!status.ok() || piece.empty()) break;
      std::unique_lock<std::mutex> lock(queue->mutex);
      queue->changed.wait(lock, [&] { return queue->pieces.size() < 2 || queue->stop; });
      if (queue->stop) return;
      queue->pieces.push_back(std::move(piece));
      queue->changed.notify_all();
    }
  } catch (const std::bad_alloc&) {
    status = Status::InvalidInput("bz2 data: out of memory while decompressing");
  }
  std::lock_guard<std::mutex> lock(queue->mutex);
  queue->status = status;
  queue->done = true;
  queue->changed.notify_all();
}

}  // namespace

Status ForEachBz2Piece(std::string_view data, size_t piece_bytes,
                       const std::function<Status(std::string_view piece)>& consume) {
  if (data.size() > (size_t{1} << 31)) {
    return Status::InvalidInput("bz2 data of " + std::to_string(data.size()) +
                                " bytes: more than calib reads (2 GiB)");
  }
  PieceQueue queue;
  std::thread producer(Produce, data, piece_bytes, &queue);
  const auto stop = [&] {
    {
      std::lock_guard<std::mutex> lock(queue.mutex);
      queue.stop = true;
    }
    queue.changed.notify_all();
    producer.join();
  };
  Status result = Status::Ok();
  try {
    while (result.ok()) {
      std::string piece;
      {
        std::unique_lock<std::mutex> lock(queue.mutex);
        queue.changed.wait(lock, [&] { return !queue.pieces.empty() || queue.done; });
        if (queue.pieces.empty()) {
          result = queue.status;
          break;
        }
        piece = std::move(queue.pieces.front());
        queue.pieces.pop_front();
        queue.changed.notify_all();
      }
      result = consume(piece);
    }
  } catch (...) {
    stop();
    throw;
  }
  stop();
  return result;
}

}  // namespace calib
