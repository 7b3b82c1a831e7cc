#include <calib/core/bz2_decompress.h>
#include <calib/core/scan/csm_log.h>
#include <calib/core/text_file.h>

#include <filesystem>
#include <string>
#include <string_view>

// CSM laser logs as files: told apart from other inputs, read plain or bzip2-compressed in pieces
// (the parsing is csm_log.cc's).
namespace calib {
namespace {

// The bytes read to tell the format (after decompression).
constexpr size_t kSniffBytes = 64 * 1024;
// A whole log decompresses to at most this much.
constexpr size_t kMaxTextBytes = size_t{8} << 30;
// The log is read in pieces of this much text.
constexpr size_t kPieceBytes = size_t{4} << 20;

bool IsBz2(std::string_view bytes) { return bytes.substr(0, 3) == "BZh"; }

}  // namespace

bool IsBz2File(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  return IsBz2(ReadFileHead(path, 3));
}

bool LooksLikeCsmLog(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  const std::string plain = ReadFileHead(path, kSniffBytes);
  std::string_view head = plain;
  std::string unpacked;
  if (IsBz2(plain)) {  // The compressed head may need more than kSniffBytes of the file.
    const StatusOr<MappedFile> file = MappedFile::Open(path);
    bool ended = false;
    if (!file.ok() || !Bz2Decompress(file->text(), {kSniffBytes, true}, &unpacked, &ended).ok()) {
      return false;
    }
    head = unpacked;
  }
  const size_t first = head.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos || head[first] != '{') return false;
  // The first object's keys: a tuple file's are T, phi_l, ...
  const size_t next = head.find("}{", first);
  const std::string_view object =
      head.substr(first, next == std::string_view::npos ? head.size() : next - first);
  return object.find("\"readings\"") != std::string_view::npos;
}

StatusOr<RobotMessages> ReadCsmLogText(std::string_view text, const std::string& source) {
  CsmLogReader reader(source);
  CALIB_RETURN_IF_ERROR(reader.Feed(text));
  return reader.Finish();
}

StatusOr<RobotMessages> ReadCsmLog(const std::string& path) {
  CALIB_ASSIGN_OR_RETURN(const MappedFile file, MappedFile::Open(path));
  CsmLogReader reader(path);
  std::string_view text = file.text();
  if (!IsBz2(text)) {
    // In pieces, each dropped from memory once read.
    while (!text.empty()) {
      const std::string_view piece = text.substr(0, kPieceBytes);
      CALIB_RETURN_IF_ERROR(reader.Feed(piece));
      file.Release(piece.data(), piece.data() + piece.size());
      text.remove_prefix(piece.size());
    }
    return reader.Finish();
  }
  // Decompressed on a second thread while the pieces are parsed, never held whole.
  size_t total = 0;
  const Status read = ForEachBz2Piece(text, kPieceBytes, [&](std::string_view piece) {
    total += piece.size();
    if (total > kMaxTextBytes) {
      return Status::InvalidInput(path + ": decompresses to more than " +
                                  std::to_string(kMaxTextBytes >> 30) + " GiB");
    }
    return reader.Feed(piece);
  });
  if (!read.ok()) {
    // The reader's messages name the file; the decompressor's do not.
    return read.message().rfind(path, 0) == 0 ? read
                                              : Status::InvalidInput(path + ": " + read.message());
  }
  return reader.Finish();
}

}  // namespace calib
