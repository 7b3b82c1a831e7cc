#include <calib/core/bag/mcap_records.h>
#include <lz4frame.h>
#include <zstd.h>

#include <array>
#include <cstdio>
#include <cstring>

namespace calib {
namespace mcap {
namespace {

// Chunks larger than this are refused rather than allocated (rosbag2 writes chunks of ~1 MB).
constexpr uint64_t kMaxChunkBytes = uint64_t{1} << 28;

// "Chunk record", "record of opcode 0x4d".
std::string RecordName(uint8_t opcode) {
  static const char* const kNames[] = {nullptr,      "Header",           "Footer",
                                       "Schema",     "Channel",          "Message",
                                       "Chunk",      "Message Index",    "Chunk Index",
                                       "Attachment", "Attachment Index", "Statistics",
                                       "Metadata",   "Metadata Index",   "Summary Offset",
                                       "Data End"};
  if (opcode > 0 && opcode < sizeof(kNames) / sizeof(kNames[0])) {
    return std::string(kNames[opcode]) + " record";
  }
  char hex[8];
  std::snprintf(hex, sizeof(hex), "0x%02x", opcode);
  return std::string("record of opcode ") + hex;
}

// CRC-32 (IEEE 802.3, reflected, as zlib computes it), eight bytes a step ("slicing-by-8":
// table k maps a byte to its CRC contribution k bytes further on).
uint32_t Crc32(const uint8_t* data, uint64_t size) {
  using Tables = std::array<std::array<uint32_t, 256>, 8>;
  static const Tables kTables = [] {
    Tables t{};
    for (uint32_t i = 0; i < 256; ++i) {
      uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[0][i] = c;
    }
    for (int k = 1; k < 8; ++k) {
      for (int i = 0; i < 256; ++i) t[k][i] = (t[k - 1][i] >> 8) ^ t[0][t[k - 1][i] & 0xFF];
    }
    return t;
  }();
  uint32_t crc = 0xFFFFFFFFu;
  uint64_t i = 0;
  for (; i + 8 <= size; i += 8) {
    const uint32_t lo = crc ^ (data[i] | data[i + 1] << 8 | data[i + 2] << 16 |
                               static_cast<uint32_t>(data[i + 3]) << 24);
    crc = kTables[7][lo & 0xFF] ^ kTables[6][(lo >> 8) & 0xFF] ^ kTables[5][(lo >> 16) & 0xFF] ^
          kTables[4][lo >> 24] ^ kTables[3][data[i + 4]] ^ kTables[2][data[i + 5]] ^
          kTables[1][data[i + 6]] ^ kTables[0][data[i + 7]];
  }
  for (; i < size; ++i) crc = kTables[0][(crc ^ data[i]) & 0xFF] ^ (crc >> 8);
  return crc ^ 0xFFFFFFFFu;
}

// A little-endian cursor over one record's content; the first overrun sticks and names the field.
class Fields {
 public:
  explicit Fields(const RecordView& record) : record_(record) {}

  template <typename T>
  T Int(const char* field) {
    T value = 0;
    if (!Need(sizeof(T), field)) return value;
    for (size_t i = 0; i < sizeof(T); ++i) {
      value |= static_cast<T>(static_cast<T>(record_.content[pos_ + i]) << (8 * i));
    }
    pos_ += sizeof(T);
    return value;
  }
  std::string String(const char* field) {
    const uint32_t n = Int<uint32_t>(field);
    if (!Need(n, field)) return {};
    std::string s(reinterpret_cast<const char*>(record_.content + pos_), n);
    pos_ += n;
    return s;
  }
  // Map<uint16, uint64>: a u32 byte length, then the pairs.
  std::map<uint16_t, uint64_t> IdMap(const char* field) {
    std::map<uint16_t, uint64_t> map;
    const uint32_t n = Int<uint32_t>(field);
    if (!Need(n, field)) return map;
    if (n % 10 != 0) return Fail(field, "a byte length that is not a whole number of entries"), map;
    for (uint32_t i = 0; i < n / 10; ++i) {
      const uint16_t key = Int<uint16_t>(field);
      map[key] = Int<uint64_t>(field);
    }
    return map;
  }
  void Skip(uint64_t n, const char* field) {
    if (Need(n, field)) pos_ += n;
  }
  uint64_t remaining() const { return record_.length - pos_; }
  const uint8_t* here() const { return record_.content + pos_; }
  Status status() const { return status_; }

 private:
  bool Need(uint64_t n, const char* field) {
    if (!status_.ok()) return false;
    if (n > record_.length - pos_) return Fail(field, "content that ends before it"), false;
    return true;
  }
  void Fail(const char* field, const std::string& what) {
    status_ = Status::InvalidInput(RecordName(record_.opcode) + " at byte " +
                                   std::to_string(record_.offset) + ": field '" + field +
                                   "' at content byte " + std::to_string(pos_) + " has " + what);
  }

  const RecordView& record_;
  uint64_t pos_ = 0;
  Status status_;
};

Status Decompressed(const ChunkRecord& chunk, size_t size, const char* what) {
  if (size == chunk.uncompressed_size) return Status::Ok();
  return Status::InvalidInput(
      std::string(what) + " chunk holds " + std::to_string(size) + " bytes of records, not the " +
      std::to_string(chunk.uncompressed_size) + " its uncompressed_size declares");
}

Status Zstd(const ChunkRecord& chunk, std::vector<uint8_t>* out) {
  const unsigned long long framed = ZSTD_getFrameContentSize(chunk.records, chunk.records_size);
  if (framed == ZSTD_CONTENTSIZE_ERROR) return Status::InvalidInput("zstd chunk data corrupt");
  // A size the frame does not confirm is trusted only up to a ratio no real bag reaches.
  const bool confirmed = framed != ZSTD_CONTENTSIZE_UNKNOWN && framed == chunk.uncompressed_size;
  if (!confirmed && chunk.uncompressed_size > 4096 * chunk.records_size + (1 << 20)) {
    return Status::InvalidInput("zstd chunk of " + std::to_string(chunk.records_size) +
                                " bytes claims " + std::to_string(chunk.uncompressed_size) +
                                " uncompressed bytes");
  }
  out->resize(chunk.uncompressed_size);
  const size_t n = ZSTD_decompress(out->data(), out->size(), chunk.records, chunk.records_size);
  if (ZSTD_isError(n)) {
    return Status::InvalidInput(std::string("zstd chunk data corrupt: ") + ZSTD_getErrorName(n));
  }
  return Decompressed(chunk, n, "zstd");
}

Status Lz4Frame(const ChunkRecord& chunk, std::vector<uint8_t>* out) {
  if (chunk.uncompressed_size > 256 * chunk.records_size + (1 << 16)) {
    return Status::InvalidInput("lz4 chunk of " + std::to_string(chunk.records_size) +
                                " bytes claims " + std::to_string(chunk.uncompressed_size) +
                                " uncompressed bytes");
  }
  out->resize(chunk.uncompressed_size);
  LZ4F_dctx* dctx = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&dctx, LZ4F_VERSION))) {
    return Status::Internal("lz4: cannot create a decompression context");
  }
  size_t in = 0, produced = 0, hint = 1;
  while (hint != 0 && in < chunk.records_size) {
    size_t dst_bytes = out->size() - produced, src_bytes = chunk.records_size - in;
    hint = LZ4F_decompress(dctx, out->data() + produced, &dst_bytes, chunk.records + in, &src_bytes,
                           nullptr);
    if (LZ4F_isError(hint)) {
      LZ4F_freeDecompressionContext(dctx);
      return Status::InvalidInput(std::string("lz4 chunk data corrupt: ") +
                                  LZ4F_getErrorName(hint));
    }
    if (dst_bytes == 0 && src_bytes == 0) break;  // No progress: output full or input stuck.
    in += src_bytes;
    produced += dst_bytes;
  }
  LZ4F_freeDecompressionContext(dctx);
  if (hint != 0) return Status::InvalidInput("lz4 chunk data end inside their frame");
  return Decompressed(chunk, produced, "lz4");
}

}  // namespace

Status ReadRecordAt(const uint8_t* data, uint64_t size, uint64_t offset, RecordView* record) {
  if (offset > size || size - offset < kRecordPrefixBytes) {
    return Status::InvalidInput("truncated: record at byte " + std::to_string(offset) +
                                " runs past the end at byte " + std::to_string(size));
  }
  record->opcode = data[offset];
  record->offset = offset;
  record->length = 0;
  for (int i = 0; i < 8; ++i) record->length |= uint64_t{data[offset + 1 + i]} << (8 * i);
  if (record->length > size - offset - kRecordPrefixBytes) {
    return Status::InvalidInput("truncated: " + RecordName(record->opcode) + " at byte " +
                                std::to_string(offset) + " of " + std::to_string(record->length) +
                                " bytes runs past the end at byte " + std::to_string(size));
  }
  record->content = data + offset + kRecordPrefixBytes;
  return Status::Ok();
}

Status ParseSchema(const RecordView& record, SchemaRecord* schema) {
  Fields f(record);
  schema->id = f.Int<uint16_t>("id");
  schema->name = f.String("name");
  schema->encoding = f.String("encoding");
  const uint32_t size = f.Int<uint32_t>("data");
  const uint8_t* data = f.here();
  f.Skip(size, "data");
  if (f.status().ok()) schema->data.assign(reinterpret_cast<const char*>(data), size);
  return f.status();
}

Status ParseChannel(const RecordView& record, ChannelRecord* channel) {
  Fields f(record);
  channel->id = f.Int<uint16_t>("id");
  channel->schema_id = f.Int<uint16_t>("schema_id");
  channel->topic = f.String("topic");
  channel->message_encoding = f.String("message_encoding");
  return f.status();  // The metadata map is not needed.
}

Status ParseMessage(const RecordView& record, MessageRecord* message) {
  Fields f(record);
  message->channel_id = f.Int<uint16_t>("channel_id");
  f.Int<uint32_t>("sequence");
  message->log_time_ns = f.Int<uint64_t>("log_time");
  f.Int<uint64_t>("publish_time");
  message->data = f.here();
  message->size = f.remaining();
  return f.status();
}

Status ParseChunk(const RecordView& record, ChunkRecord* chunk) {
  Fields f(record);
  f.Int<uint64_t>("message_start_time");
  f.Int<uint64_t>("message_end_time");
  chunk->uncompressed_size = f.Int<uint64_t>("uncompressed_size");
  chunk->uncompressed_crc = f.Int<uint32_t>("uncompressed_crc");
  chunk->compression = f.String("compression");
  chunk->records_size = f.Int<uint64_t>("records");
  chunk->records = f.here();
  f.Skip(chunk->records_size, "records");
  CALIB_RETURN_IF_ERROR(f.status());
  if (chunk->uncompressed_size > kMaxChunkBytes) {
    return Status::InvalidInput("Chunk record at byte " + std::to_string(record.offset) +
                                ": uncompressed_size " + std::to_string(chunk->uncompressed_size) +
                                " is beyond the 256 MiB this reader accepts");
  }
  return Status::Ok();
}

Status ParseChunkIndex(const RecordView& record, ChunkIndexRecord* index) {
  Fields f(record);
  f.Int<uint64_t>("message_start_time");
  f.Int<uint64_t>("message_end_time");
  index->chunk_start_offset = f.Int<uint64_t>("chunk_start_offset");
  index->chunk_length = f.Int<uint64_t>("chunk_length");
  index->message_index_offsets = f.IdMap("message_index_offsets");
  f.Int<uint64_t>("message_index_length");
  index->compression = f.String("compression");
  return f.status();
}

Status ParseStatistics(const RecordView& record, StatisticsRecord* statistics) {
  Fields f(record);
  statistics->message_count = f.Int<uint64_t>("message_count");
  f.Int<uint16_t>("schema_count");
  f.Int<uint32_t>("channel_count");
  f.Int<uint32_t>("attachment_count");
  f.Int<uint32_t>("metadata_count");
  statistics->chunk_count = f.Int<uint32_t>("chunk_count");
  f.Int<uint64_t>("message_start_time");
  f.Int<uint64_t>("message_end_time");
  statistics->channel_message_counts = f.IdMap("channel_message_counts");
  return f.status();
}

Status ParseFooter(const RecordView& record, FooterRecord* footer) {
  Fields f(record);
  footer->summary_start = f.Int<uint64_t>("summary_start");
  footer->summary_offset_start = f.Int<uint64_t>("summary_offset_start");
  return f.status();
}

Status CountMessageIndexEntries(const RecordView& record, uint64_t* count) {
  Fields f(record);
  f.Int<uint16_t>("channel_id");
  const uint32_t bytes = f.Int<uint32_t>("records");
  f.Skip(bytes, "records");
  *count = bytes / 16;  // (log_time u64, offset u64) pairs.
  return f.status();
}

Status DecompressChunk(const ChunkRecord& chunk, std::vector<uint8_t>* out) {
  if (chunk.compression.empty()) {
    if (chunk.records_size != chunk.uncompressed_size) {
      return Decompressed(chunk, chunk.records_size, "uncompressed");
    }
    out->assign(chunk.records, chunk.records + chunk.records_size);
  } else if (chunk.compression == "zstd") {
    CALIB_RETURN_IF_ERROR(Zstd(chunk, out));
  } else if (chunk.compression == "lz4") {
    CALIB_RETURN_IF_ERROR(Lz4Frame(chunk, out));
  } else {
    return Status::InvalidInput("unknown compression '" + chunk.compression + "'");
  }
  // A CRC of zero means none was computed.
  if (chunk.uncompressed_crc != 0 && Crc32(out->data(), out->size()) != chunk.uncompressed_crc) {
    return Status::InvalidInput("its records do not match their CRC-32 (corrupt data)");
  }
  return Status::Ok();
}

}  // namespace mcap
}  // namespace calib
