#ifndef CALIB_CORE_BAG_MCAP_RECORDS_H_
#define CALIB_CORE_BAG_MCAP_RECORDS_H_

#include <calib/core/status.h>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

// The records of an MCAP file (https://mcap.dev/spec) a ROS 2 bag reader needs, parsed from
// bytes already in memory. Every record is <opcode u8><content length u64><content>; integers are
// little-endian, strings and maps carry a u32 byte length. Parsers check every length against
// the bytes that remain and fail with a message naming the record and the field (the caller
// puts the file name in front).
namespace calib {
namespace mcap {

constexpr uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};
constexpr uint64_t kRecordPrefixBytes = 9;  // Opcode and content length.
constexpr uint64_t kFooterContentBytes = 20;

enum Opcode : uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kDataEnd = 0x0F,
};

// One record in a byte range; offset is its opcode's position in that range.
struct RecordView {
  uint8_t opcode = 0;
  uint64_t offset = 0;
  const uint8_t* content = nullptr;
  uint64_t length = 0;
  uint64_t end() const { return offset + kRecordPrefixBytes + length; }
};

// The record at `offset` of [data, data + size); fails when its prefix or content runs past the
// end ("record at byte 1234 (opcode 0x06) of 5678 bytes runs past the end at byte 4000").
Status ReadRecordAt(const uint8_t* data, uint64_t size, uint64_t offset, RecordView* record);

struct SchemaRecord {
  uint16_t id = 0;
  std::string name, encoding;
  std::string data;  // The definition (for ros2msg and ros1msg, the .msg text).
};

struct ChannelRecord {
  uint16_t id = 0, schema_id = 0;
  std::string topic, message_encoding;
};

struct MessageRecord {
  uint16_t channel_id = 0;
  uint64_t log_time_ns = 0;
  const uint8_t* data = nullptr;
  uint64_t size = 0;
};

struct ChunkRecord {
  uint64_t uncompressed_size = 0;
  uint32_t uncompressed_crc = 0;
  std::string compression;
  const uint8_t* records = nullptr;
  uint64_t records_size = 0;
};

struct ChunkIndexRecord {
  uint64_t chunk_start_offset = 0, chunk_length = 0;
  std::map<uint16_t, uint64_t> message_index_offsets;  // Channel id → its Message Index record.
  std::string compression;
};

struct StatisticsRecord {
  uint64_t message_count = 0;
  uint32_t chunk_count = 0;
  std::map<uint16_t, uint64_t> channel_message_counts;
};

struct FooterRecord {
  uint64_t summary_start = 0, summary_offset_start = 0;
};

Status ParseSchema(const RecordView& record, SchemaRecord* schema);
Status ParseChannel(const RecordView& record, ChannelRecord* channel);
Status ParseMessage(const RecordView& record, MessageRecord* message);
Status ParseChunk(const RecordView& record, ChunkRecord* chunk);
Status ParseChunkIndex(const RecordView& record, ChunkIndexRecord* index);
Status ParseStatistics(const RecordView& record, StatisticsRecord* statistics);
Status ParseFooter(const RecordView& record, FooterRecord* footer);
// The number of (log_time, offset) entries of a Message Index record.
Status CountMessageIndexEntries(const RecordView& record, uint64_t* count);

// The chunk's records, uncompressed into `out` (compression "", "zstd" or "lz4", the LZ4 frame
// format); fails on an unknown compression ("unknown compression 'brotli'"), corrupt data, a
// size other than the chunk's uncompressed_size or a CRC-32 other than its uncompressed_crc.
Status DecompressChunk(const ChunkRecord& chunk, std::vector<uint8_t>* out);

}  // namespace mcap
}  // namespace calib

#endif  // CALIB_CORE_BAG_MCAP_RECORDS_H_
