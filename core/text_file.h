#ifndef CALIB_CORE_TEXT_FILE_H_
#define CALIB_CORE_TEXT_FILE_H_

#include <calib/core/status.h>

#include <cstdint>
#include <functional>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace calib {

// Bounds every text reader keeps, so that a hostile file costs an error, not the machine.
// A record longer than this (a CSV line, a JSON tuple) is refused: real ones hold < 200 bytes,
// a wide scan row of a few thousand beams some tens of kB.
constexpr size_t kMaxLineBytes = size_t{1} << 20;
// Columns of a CSV header: a wide scan CSV names one per beam (a few thousand at most).
constexpr size_t kMaxCsvColumns = 10000;
// A NUL byte within this many leading bytes marks a binary file (checked before any parsing).
constexpr size_t kTextCheckBytes = 64 * 1024;

// A parser calls this with a range [begin, end) of its text that it will not read again: a mapped
// file then drops those pages, so that a long log's parse keeps a window of the file resident
// instead of all of it (a million intervals: 200 MB). Ranges of one parse do not overlap, and
// threads parsing disjoint parts of a text may call it at once.
using ReleaseText = std::function<void(const char* begin, const char* end)>;
// Parsers call it at most this often (per thread, for kReleaseTextBytes / threads).
constexpr size_t kReleaseTextBytes = size_t{16} << 20;

// A file's bytes, read-only and owned: a regular file is mapped (MAP_PRIVATE, PROT_READ), so that
// no zero-filled copy is made and only the pages parsed are read; anything else (a pipe) is read
// into memory. Empty files give an empty view. Move-only.
class MappedFile {
 public:
  MappedFile() = default;
  MappedFile(MappedFile&& other) noexcept { *this = std::move(other); }
  MappedFile& operator=(MappedFile&& other) noexcept;
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;
  ~MappedFile();

  // Any bytes (a bag). Messages name the path: "no such file", "is a directory", "cannot read".
  static StatusOr<MappedFile> Open(const std::string& path);
  // A text file: as Open, and refused as "not a text file" when a NUL byte appears in its first
  // kTextCheckBytes (a pipe is checked as it is read, so that /dev/zero is not read forever).
  static StatusOr<MappedFile> OpenText(const std::string& path);

  std::string_view text() const { return {data_, size_}; }
  const uint8_t* data() const { return reinterpret_cast<const uint8_t*>(data_); }
  uint64_t size() const { return size_; }
  const std::string& path() const { return path_; }
  // Drops the resident pages wholly inside [begin, end) (pointers into text()); they read back
  // from the file if touched again. No effect on a file read into memory. Thread-safe.
  void Release(const char* begin, const char* end) const;
  ReleaseText Releaser() const {
    return [this](const char* begin, const char* end) { Release(begin, end); };
  }

 private:
  static StatusOr<MappedFile> OpenImpl(const std::string& path, bool text);
  Status ReadStream(int fd, bool text);
  void Unmap();

  std::string path_;
  const char* data_ = nullptr;
  size_t size_ = 0;
  bool mapped_ = false;
  std::string owned_;  // The bytes of a file that could not be mapped.
};

// About how many times `byte` occurs in `text`, to reserve a reader's records: exact within its
// first MB, beyond that extrapolated from it with 5 % to spare (a capacity never filled costs
// address space, not memory; a full count would read a long file twice).
size_t EstimateByteCount(std::string_view text, char byte);

// "FILE: not a text file: a NUL byte at byte N (binary data?)" when one appears in the first
// kTextCheckBytes of `bytes`; OK otherwise.
Status CheckTextBytes(std::string_view bytes, const std::string& source);

// Reads a whole file into `text` (a copy of the mapped bytes; kept for callers that need a
// std::string). Text readers use MappedFile::OpenText instead.
Status ReadWholeFile(const std::string& path, std::string* text);

// Up to the first `count` bytes of a file (fewer when it is shorter; none when it cannot be read),
// read rather than mapped: the sniffers that tell formats apart run while another thread may
// hold the address space's lock (tools/process_memory.h), which a mapping would wait for.
std::string ReadFileHead(const std::string& path, size_t count);

// Writes `text` to `path`, replacing it.
Status WriteWholeFile(const std::string& path, const std::string& text);

// A line or record number kept in an int field (LaserInterval::line, ...): counted in 64 bits by
// the readers, saturated here rather than wrapped.
inline int SaturatedInt(int64_t n) {
  return n > std::numeric_limits<int>::max() ? std::numeric_limits<int>::max()
                                             : static_cast<int>(n);
}

// "FILE: out of memory reading it (N bytes): ..." for an allocation failure inside a reader.
Status OutOfMemory(const std::string& source, const char* what);

// Runs `read` (returning a Status or StatusOr) and turns an allocation failure inside it into an
// error naming `source`: a reader never aborts, whatever the input.
template <typename Read>
auto GuardAllocation(const std::string& source, Read&& read) -> decltype(read()) {
  try {
    return read();
  } catch (const std::bad_alloc& e) {
    return OutOfMemory(source, e.what());
  } catch (const std::length_error& e) {
    return OutOfMemory(source, e.what());
  }
}

}  // namespace calib

#endif  // CALIB_CORE_TEXT_FILE_H_
