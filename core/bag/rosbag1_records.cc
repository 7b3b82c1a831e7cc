#include <calib/core/bag/rosbag1_records.h>
#include <calib/core/bz2_decompress.h>
#include <lz4frame.h>

#include <algorithm>
#include <memory>

namespace calib::rosbag1 {
namespace {

// Chunks larger than this are refused rather than decompressed.
constexpr uint32_t kMaxChunkBytes = uint32_t{1} << 28;

std::string Quoted(std::string_view s) { return "'" + std::string(s) + "'"; }

// The output buffer grows as the decompressor fills it, up to the chunk's stated size, so that
// a corrupt size field costs no more memory than the data really decompress to.
void Grow(std::string* out, size_t used, uint32_t size) {
  const size_t next = std::max<size_t>(used * 2, size_t{1} << 16);
  out->resize(std::min<size_t>(next, size));
}

Status DecompressBz2(std::string_view data, uint32_t size, std::string* out) {
  // One byte more than stated: output that reaches it says the size field is wrong.
  bool ended = false;
  CALIB_RETURN_IF_ERROR(Bz2Decompress(data, {size_t{size} + 1, false}, out, &ended));
  if (out->size() > size) {
    return Status::InvalidInput("bz2 data decompress to more than the stated size " +
                                std::to_string(size));
  }
  if (out->size() != size) {
    return Status::InvalidInput("bz2 data decompress to " + std::to_string(out->size()) +
                                " bytes, the chunk states " + std::to_string(size));
  }
  return Status::Ok();
}

Status DecompressLz4(std::string_view data, uint32_t size, std::string* out) {
  LZ4F_dctx* raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) {
    return Status::Internal("lz4: cannot create a decompression context");
  }
  std::unique_ptr<LZ4F_dctx, LZ4F_errorCode_t (*)(LZ4F_dctx*)> ctx(raw,
                                                                   LZ4F_freeDecompressionContext);
  size_t in_pos = 0, used = 0;
  out->clear();
  while (true) {
    if (used == out->size()) {
      if (used == size) break;
      Grow(out, used, size);
    }
    size_t out_size = out->size() - used, in_size = data.size() - in_pos;
    const size_t hint = LZ4F_decompress(ctx.get(), out->data() + used, &out_size,
                                        data.data() + in_pos, &in_size, nullptr);
    if (LZ4F_isError(hint)) {
      return Status::InvalidInput(std::string("lz4 data are corrupt (") + LZ4F_getErrorName(hint) +
                                  ")");
    }
    used += out_size;
    in_pos += in_size;
    if (hint == 0) break;  // The frame ended.
    if (out_size == 0 && in_size == 0) {
      return Status::InvalidInput("lz4 data end before their frame does (truncated)");
    }
  }
  if (used == size && in_pos < data.size()) {
    // Full before the frame's end mark was consumed: whatever is left must decode to nothing.
    char probe = 0;
    size_t out_size = 1, in_size = data.size() - in_pos;
    const size_t hint =
        LZ4F_decompress(ctx.get(), &probe, &out_size, data.data() + in_pos, &in_size, nullptr);
    if (LZ4F_isError(hint) || out_size != 0) {
      return Status::InvalidInput("lz4 data decompress to more than the stated size " +
                                  std::to_string(size));
    }
  }
  out->resize(used);
  if (used != size) {
    return Status::InvalidInput("lz4 data decompress to " + std::to_string(used) +
                                " bytes, the chunk states " + std::to_string(size));
  }
  return Status::Ok();
}

}  // namespace

StatusOr<FieldList> FieldList::Parse(std::string_view bytes) {
  FieldList list;
  size_t pos = 0;
  while (pos < bytes.size()) {
    if (bytes.size() - pos < 4) {
      return Status::InvalidInput("header field at byte " + std::to_string(pos) +
                                  " has no room for its length");
    }
    const uint32_t len = LoadU32(bytes.data() + pos);
    pos += 4;
    if (len > bytes.size() - pos) {
      return Status::InvalidInput("header field at byte " + std::to_string(pos - 4) + " is " +
                                  std::to_string(len) + " bytes long, only " +
                                  std::to_string(bytes.size() - pos) + " are left");
    }
    const std::string_view field = bytes.substr(pos, len);
    const size_t eq = field.find('=');
    if (eq == std::string_view::npos) {
      return Status::InvalidInput("header field at byte " + std::to_string(pos - 4) +
                                  " has no '='");
    }
    list.fields_.emplace_back(field.substr(0, eq), field.substr(eq + 1));
    pos += len;
  }
  return list;
}

bool FieldList::Has(std::string_view name) const {
  return std::any_of(fields_.begin(), fields_.end(),
                     [&](const auto& f) { return f.first == name; });
}

StatusOr<std::string_view> FieldList::Bytes(std::string_view name) const {
  for (const auto& [key, value] : fields_) {
    if (key == name) return value;
  }
  return Status::InvalidInput("no field " + Quoted(name));
}

StatusOr<std::string_view> FieldList::Sized(std::string_view name, size_t size) const {
  CALIB_ASSIGN_OR_RETURN(std::string_view value, Bytes(name));
  if (value.size() != size) {
    return Status::InvalidInput("field " + Quoted(name) + " has " + std::to_string(value.size()) +
                                " bytes, not " + std::to_string(size));
  }
  return value;
}

StatusOr<uint8_t> FieldList::Op() const {
  CALIB_ASSIGN_OR_RETURN(std::string_view value, Sized("op", 1));
  return static_cast<uint8_t>(value[0]);
}

StatusOr<uint32_t> FieldList::U32(std::string_view name) const {
  CALIB_ASSIGN_OR_RETURN(std::string_view value, Sized(name, 4));
  return LoadU32(value.data());
}

StatusOr<uint64_t> FieldList::U64(std::string_view name) const {
  CALIB_ASSIGN_OR_RETURN(std::string_view value, Sized(name, 8));
  return LoadU64(value.data());
}

StatusOr<Time> FieldList::TimeField(std::string_view name) const {
  CALIB_ASSIGN_OR_RETURN(std::string_view value, Sized(name, 8));
  return Time{LoadU32(value.data()), LoadU32(value.data() + 4)};
}

Status ParseRecord(std::string_view buffer, uint64_t base, uint64_t* pos, Record* record) {
  const uint64_t start = *pos;
  const auto where = [&] { return "record at byte " + std::to_string(base + start) + ": "; };
  const auto length = [&](const char* what, uint64_t at, uint32_t* len) -> Status {
    if (at > buffer.size() || buffer.size() - at < 4) {
      return Status::InvalidInput(where() + "truncated: the " + what + " length at byte " +
                                  std::to_string(base + at) + " is cut off by the end at byte " +
                                  std::to_string(base + buffer.size()));
    }
    *len = LoadU32(buffer.data() + at);
    if (*len > buffer.size() - at - 4) {
      return Status::InvalidInput(where() + "truncated: its " + what + " of " +
                                  std::to_string(*len) + " bytes at byte " +
                                  std::to_string(base + at + 4) + " runs past the end at byte " +
                                  std::to_string(base + buffer.size()));
    }
    return Status::Ok();
  };
  uint32_t header_len = 0, data_len = 0;
  CALIB_RETURN_IF_ERROR(length("header", start, &header_len));
  const uint64_t data_at = start + 4 + header_len;
  CALIB_RETURN_IF_ERROR(length("data", data_at, &data_len));
  auto header = FieldList::Parse(buffer.substr(start + 4, header_len));
  if (!header.ok()) return header.status().Prefixed(where());
  auto op = header->Op();
  if (!op.ok()) return op.status().Prefixed(where());
  record->header = std::move(header).value();
  record->op = *op;
  record->data = buffer.substr(data_at + 4, data_len);
  *pos = data_at + 4 + data_len;
  return Status::Ok();
}

Status BagFile::Open(const std::string& path) {
  StatusOr<MappedFile> file = MappedFile::Open(path);
  if (!file.ok()) {
    // Messages here do not name the file: the reader puts it in front.
    const std::string& message = file.message();
    return Status(file.code(), message.compare(0, path.size(), path) == 0
                                   ? message.substr(std::min(message.size(), path.size() + 2))
                                   : message);
  }
  file_ = std::move(file).value();
  bytes_ = file_.text();
  return Status::Ok();
}

Status BagFile::ReadAt(uint64_t pos, uint64_t n, std::string* out) {
  const uint64_t size = bytes_.size();
  if (pos > size || n > size - pos) {
    return Status::InvalidInput("truncated: " + std::to_string(n) + " bytes at byte " +
                                std::to_string(pos) + " run past the end of the file at byte " +
                                std::to_string(size));
  }
  out->assign(bytes_.data() + pos, n);
  return Status::Ok();
}

Status BagFile::ReadRecord(uint64_t* pos, bool with_data, std::string* storage, Record* record) {
  const uint64_t start = *pos;
  const auto where = [&] { return "record at byte " + std::to_string(start) + ": "; };
  const uint64_t file_size = bytes_.size();
  const auto truncated = [&](const char* what, uint64_t at, uint64_t len) {
    return Status::InvalidInput(
        where() + "truncated: its " + what + " of " + std::to_string(len) + " bytes at byte " +
        std::to_string(at) + " runs past the end of the file at byte " + std::to_string(file_size));
  };
  if (start > file_size || file_size - start < 4) return truncated("header length", start, 4);
  CALIB_RETURN_IF_ERROR(ReadAt(start, 4, storage));
  const uint64_t header_len = LoadU32(storage->data());
  if (header_len + 4 > file_size - start - 4) {
    return truncated("header and data length", start + 4, header_len + 4);
  }
  CALIB_RETURN_IF_ERROR(ReadAt(start, 4 + header_len + 4, storage));
  const uint64_t data_len = LoadU32(storage->data() + 4 + header_len);
  const uint64_t data_at = start + 8 + header_len;
  if (data_len > file_size - data_at) return truncated("data", data_at, data_len);
  if (with_data) CALIB_RETURN_IF_ERROR(ReadAt(start, 8 + header_len + data_len, storage));
  auto header = FieldList::Parse(std::string_view(*storage).substr(4, header_len));
  if (!header.ok()) return header.status().Prefixed(where());
  auto op = header->Op();
  if (!op.ok()) return op.status().Prefixed(where());
  record->header = std::move(header).value();
  record->op = *op;
  record->data = with_data ? std::string_view(*storage).substr(8 + header_len) : std::string_view();
  *pos = data_at + data_len;
  return Status::Ok();
}

Status DecompressChunk(std::string_view compression, std::string_view data, uint32_t size,
                       std::string* out) {
  if (size > kMaxChunkBytes) {
    return Status::InvalidInput("the chunk states " + std::to_string(size) +
                                " uncompressed bytes, beyond the " +
                                std::to_string(kMaxChunkBytes >> 20) +
                                " MiB this reader accepts (rosbag writes chunks of ~768 KiB)");
  }
  if (compression == "none") {
    if (data.size() != size) {
      return Status::InvalidInput("uncompressed chunk holds " + std::to_string(data.size()) +
                                  " bytes, its header states " + std::to_string(size));
    }
    out->assign(data);
    return Status::Ok();
  }
  if (compression == "bz2") return DecompressBz2(data, size, out);
  if (compression == "lz4") return DecompressLz4(data, size, out);
  return Status::InvalidInput("unknown compression " + Quoted(compression) +
                              " (known: none, bz2, lz4)");
}

}  // namespace calib::rosbag1
