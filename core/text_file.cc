#include <calib/core/text_file.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>

namespace calib {
namespace {

// Closes a descriptor on every way out.
class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) close(fd_);
  }
  int get() const { return fd_; }

 private:
  int fd_;
};

Status OpenError(const std::string& path, int error) {
  if (error == ENOENT || error == ENOTDIR) return Status::Io(path + ": no such file");
  return Status::Io(path + ": cannot open for reading: " + std::strerror(error));
}

}  // namespace

MappedFile& MappedFile::operator=(MappedFile&& other) noexcept {
  if (this == &other) return *this;
  Unmap();
  path_ = std::move(other.path_);
  owned_ = std::move(other.owned_);
  mapped_ = other.mapped_;
  size_ = other.size_;
  data_ = mapped_ ? other.data_ : owned_.data();
  other.data_ = nullptr;
  other.size_ = 0;
  other.mapped_ = false;
  return *this;
}

MappedFile::~MappedFile() { Unmap(); }

void MappedFile::Unmap() {
  if (mapped_ && data_ != nullptr) munmap(const_cast<char*>(data_), size_);
  data_ = nullptr;
  size_ = 0;
  mapped_ = false;
}

void MappedFile::Release(const char* begin, const char* end) const {
  if (!mapped_ || begin < data_ || end > data_ + size_ || !(begin < end)) return;
  const size_t page = static_cast<size_t>(sysconf(_SC_PAGESIZE));
  const size_t first = (static_cast<size_t>(begin - data_) + page - 1) / page * page;
  const size_t last = static_cast<size_t>(end - data_) / page * page;
  if (last <= first) return;
  // The mapping is private and never written: dropped pages read back from the file.
  madvise(const_cast<char*>(data_) + first, last - first, MADV_DONTNEED);
}

size_t EstimateByteCount(std::string_view text, char byte) {
  constexpr size_t kSampleBytes = size_t{1} << 20;
  const std::string_view sample = text.substr(0, kSampleBytes);
  size_t count = 0;
  for (const char* q = sample.data(); q < sample.data() + sample.size(); ++count, ++q) {
    q = static_cast<const char*>(
        std::memchr(q, byte, static_cast<size_t>(sample.data() + sample.size() - q)));
    if (q == nullptr) break;
  }
  if (sample.size() == text.size()) return count;
  const double per_byte = static_cast<double>(count) / static_cast<double>(sample.size());
  return static_cast<size_t>(1.05 * per_byte * static_cast<double>(text.size())) + 16;
}

StatusOr<MappedFile> MappedFile::Open(const std::string& path) { return OpenImpl(path, false); }

StatusOr<MappedFile> MappedFile::OpenText(const std::string& path) { return OpenImpl(path, true); }

StatusOr<MappedFile> MappedFile::OpenImpl(const std::string& path, bool text) {
  MappedFile file;
  file.path_ = path;
  Fd fd(open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (fd.get() < 0) return OpenError(path, errno);
  struct stat st;
  if (fstat(fd.get(), &st) != 0) return Status::Io(path + ": cannot read: " + std::strerror(errno));
  if (S_ISDIR(st.st_mode)) return Status::Io(path + ": is a directory, expected a file");
  // A pipe cannot be mapped; a file of size 0 may still hold bytes (/proc): both are read.
  if (!S_ISREG(st.st_mode) || st.st_size == 0) {
    CALIB_RETURN_IF_ERROR(file.ReadStream(fd.get(), text));
    return StatusOr<MappedFile>(std::move(file));
  }
  file.size_ = static_cast<size_t>(st.st_size);
  void* map = mmap(nullptr, file.size_, PROT_READ, MAP_PRIVATE, fd.get(), 0);
  if (map == MAP_FAILED) {
    file.size_ = 0;
    return Status::Io(path + ": cannot read (mmap failed: " + std::strerror(errno) + ")");
  }
  file.data_ = static_cast<const char*>(map);
  file.mapped_ = true;
  madvise(map, file.size_, MADV_SEQUENTIAL);  // Parsers run front to back.
  if (text) CALIB_RETURN_IF_ERROR(CheckTextBytes(file.text(), path));
  return StatusOr<MappedFile>(std::move(file));
}

Status MappedFile::ReadStream(int fd, bool text) {
  try {
    char buffer[1 << 16];
    bool checked = !text;
    while (true) {
      const ssize_t n = read(fd, buffer, sizeof(buffer));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) return Status::Io(path_ + ": cannot read: " + std::strerror(errno));
      if (n == 0) break;
      owned_.append(buffer, static_cast<size_t>(n));
      if (!checked && owned_.size() >= kTextCheckBytes) {
        CALIB_RETURN_IF_ERROR(CheckTextBytes(owned_, path_));
        checked = true;
      }
    }
    if (!checked) CALIB_RETURN_IF_ERROR(CheckTextBytes(owned_, path_));
  } catch (const std::bad_alloc& e) {
    owned_.clear();
    owned_.shrink_to_fit();
    return OutOfMemory(path_, e.what());
  } catch (const std::length_error& e) {
    owned_.clear();
    owned_.shrink_to_fit();
    return OutOfMemory(path_, e.what());
  }
  data_ = owned_.data();
  size_ = owned_.size();
  return Status::Ok();
}

Status CheckTextBytes(std::string_view bytes, const std::string& source) {
  const size_t n = std::min(bytes.size(), kTextCheckBytes);
  const void* nul = std::memchr(bytes.data(), '\0', n);
  if (nul == nullptr) return Status::Ok();
  const size_t at = static_cast<size_t>(static_cast<const char*>(nul) - bytes.data());
  return Status::InvalidInput(source + ": not a text file: a NUL byte at byte " +
                              std::to_string(at) +
                              " (binary data, or a file of zeros); nothing was parsed");
}

std::string ReadFileHead(const std::string& path, size_t count) {
  Fd fd(open(path.c_str(), O_RDONLY | O_CLOEXEC));
  std::string bytes;
  if (fd.get() < 0) return bytes;
  bytes.resize(count);
  size_t got = 0;
  while (got < count) {
    const ssize_t n = read(fd.get(), bytes.data() + got, count - got);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    got += static_cast<size_t>(n);
  }
  bytes.resize(got);
  return bytes;
}

Status ReadWholeFile(const std::string& path, std::string* text) {
  CALIB_ASSIGN_OR_RETURN(const MappedFile file, MappedFile::Open(path));
  return GuardAllocation(path, [&] {
    text->assign(file.text());
    return Status::Ok();
  });
}

Status WriteWholeFile(const std::string& path, const std::string& text) {
  // errno says why (no such folder, no space left on device, ...), when the system set it.
  const auto why = [] { return errno != 0 ? std::string(" (") + std::strerror(errno) + ")" : ""; };
  errno = 0;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return Status::Io(path + ": cannot open for writing" + why());
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  out.close();
  if (!out) return Status::Io(path + ": write failed" + why());
  return Status::Ok();
}

Status OutOfMemory(const std::string& source, const char* what) {
  return Status::Io(source + ": out of memory reading it (" + what +
                    "): the input is too large or malformed for the memory available");
}

}  // namespace calib
