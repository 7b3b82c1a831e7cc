#ifndef CALIB_CORE_BAG_ROSBAG1_RECORDS_H_
#define CALIB_CORE_BAG_ROSBAG1_RECORDS_H_

#include <calib/core/status.h>
#include <calib/core/text_file.h>

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

// The records of a ROS 1 bag, format 2.0: "#ROSBAG V2.0\n", then records, each
// <header_len u32><header><data_len u32><data>, all integers little-endian. A header is a sequence
// of <field_len u32>"name=value" (the value binary); its "op" field (one byte) says the kind.
namespace calib::rosbag1 {

inline constexpr std::string_view kMagic = "#ROSBAG V2.0\n";

enum Op : uint8_t {
  kOpMessageData = 0x02,  // conn u32, time; data: the serialized message.
  kOpBagHeader = 0x03,    // index_pos u64, conn_count u32, chunk_count u32; data: padding.
  kOpIndexData = 0x04,    // ver u32, conn u32, count u32; data: count × (time, offset u32).
  kOpChunk = 0x05,        // compression string, size u32 (uncompressed); data: records.
  kOpChunkInfo = 0x06,    // ver u32, chunk_pos u64, start_time, end_time, count u32;
                          // data: count × (conn u32, count u32).
  kOpConnection = 0x07,   // conn u32, topic; data: a header (topic, type, md5sum, ...).
};

// A ROS time: u32 seconds + u32 nanoseconds.
struct Time {
  uint32_t sec = 0, nsec = 0;
  double Seconds() const { return sec + nsec * 1e-9; }
  uint64_t Nanoseconds() const { return sec * uint64_t{1000000000} + nsec; }
};

// Reads little-endian integers from bytes the caller has bounds-checked.
inline uint32_t LoadU32(const char* p) {
  const auto* b = reinterpret_cast<const unsigned char*>(p);
  return uint32_t{b[0]} | uint32_t{b[1]} << 8 | uint32_t{b[2]} << 16 | uint32_t{b[3]} << 24;
}
inline uint64_t LoadU64(const char* p) { return LoadU32(p) | uint64_t{LoadU32(p + 4)} << 32; }

// The name=value fields of a record header (or of a connection's data), viewing the caller's
// bytes. Messages name the field but not the record: the caller prefixes where it is.
class FieldList {
 public:
  static StatusOr<FieldList> Parse(std::string_view bytes);

  bool Has(std::string_view name) const;
  StatusOr<std::string_view> Bytes(std::string_view name) const;
  StatusOr<uint8_t> Op() const;
  StatusOr<uint32_t> U32(std::string_view name) const;
  StatusOr<uint64_t> U64(std::string_view name) const;
  StatusOr<Time> TimeField(std::string_view name) const;

 private:
  StatusOr<std::string_view> Sized(std::string_view name, size_t size) const;
  std::vector<std::pair<std::string_view, std::string_view>> fields_;
};

// One record, viewing the buffer it was parsed from.
struct Record {
  FieldList header;
  uint8_t op = 0;
  std::string_view data;
};

// Parses the record that starts at byte *pos of `buffer` and moves *pos past it. Errors name the
// record's byte (`base` + *pos: the caller's offset of buffer[0]) and what does not fit.
Status ParseRecord(std::string_view buffer, uint64_t base, uint64_t* pos, Record* record);

// Random access to a bag file, every read bounded by the file's size: a corrupt length field
// gives an error naming its byte, never a huge allocation. Messages do not name the file.
class BagFile {
 public:
  // The file mapped read-only.
  Status Open(const std::string& path);
  // Bytes already in memory (they must outlive the BagFile).
  void OpenBytes(std::string_view bytes) { bytes_ = bytes; }
  uint64_t size() const { return bytes_.size(); }
  // Reads bytes [pos, pos + n) into *out.
  Status ReadAt(uint64_t pos, uint64_t n, std::string* out);
  // Reads the record at *pos into *storage and parses it (its data left empty unless
  // `with_data`); moves *pos past it.
  Status ReadRecord(uint64_t* pos, bool with_data, std::string* storage, Record* record);

 private:
  MappedFile file_;
  std::string_view bytes_;
};

// Decompresses a chunk's data ("none", "bz2" or "lz4", the LZ4 frame format roslz4 writes) into
// *out, which must come out exactly `size` bytes long; never allocates more than `size`.
Status DecompressChunk(std::string_view compression, std::string_view data, uint32_t size,
                       std::string* out);

}  // namespace calib::rosbag1

#endif  // CALIB_CORE_BAG_ROSBAG1_RECORDS_H_
