// ReadMcapBag: a ROS 2 bag (MCAP file, CDR messages) read without an MCAP library.
#include <calib/core/bag/mcap_records.h>
#include <calib/core/bag/robot_messages.h>
#include <calib/core/bag/ros2_collector.h>
#include <calib/core/text_file.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <utility>

namespace calib {
namespace {

using mcap::ChannelRecord;
using mcap::ChunkIndexRecord;
using mcap::RecordView;

using ros2::Channel;
using ros2::Kind;

std::string At(uint64_t offset) { return " at byte " + std::to_string(offset); }

class BagReader {
 public:
  BagReader(const uint8_t* data, uint64_t size, const BagReadOptions& options)
      : data_(data), size_(size), options_(options) {}

  Status ReadLinear();
  // Reads through the summary; *used is false (and nothing decoded) when the summary lacks the
  // statistics or indexes this needs, so that the caller scans linearly instead.
  Status ReadIndexed(const mcap::FooterRecord& footer, uint64_t footer_offset, bool* used);
  void Finish(RobotMessages* out);

 private:
  struct Summary {
    std::vector<ChunkIndexRecord> chunks;  // By offset in the file.
    mcap::StatisticsRecord statistics;
    bool have_statistics = false;
  };
  Status ReadSummary(const mcap::FooterRecord& footer, uint64_t footer_offset, Summary* summary);
  Status OnRecord(const RecordView& record, const std::string& where);
  Status OnChannel(const RecordView& record);
  Status OnMessage(const RecordView& record, const std::string& where);
  Status ForEachInChunk(const RecordView& chunk, const std::string& where);
  Status CountIndexed(const ChunkIndexRecord& index, uint64_t* count, bool* known);

  const uint8_t* data_;
  uint64_t size_;
  const BagReadOptions& options_;
  std::map<uint16_t, mcap::SchemaRecord> schemas_;  // Names normalised.
  std::map<uint16_t, Channel> channels_;
  int64_t next_record_ = 0;
  bool count_messages_ = true;  // False when the summary's statistics gave the counts.
  std::vector<uint8_t> chunk_buffer_;
  ros2::MessageCollector collector_;
};

Status BagReader::OnChannel(const RecordView& record) {
  ChannelRecord c;
  CALIB_RETURN_IF_ERROR(mcap::ParseChannel(record, &c));
  const auto schema = schemas_.find(c.schema_id);
  const int64_t count = channels_[c.id].message_count;
  channels_[c.id] = schema == schemas_.end()
                        ? ros2::MakeChannel(c.topic, "", c.message_encoding, options_)
                        : ros2::MakeChannel(c.topic, schema->second.name, c.message_encoding,
                                            options_, schema->second.data);
  channels_[c.id].message_count = count;  // A channel repeated in the summary keeps its count.
  return Status::Ok();
}

Status BagReader::OnRecord(const RecordView& record, const std::string& where) {
  switch (record.opcode) {
    case mcap::kSchema: {
      mcap::SchemaRecord schema;
      CALIB_RETURN_IF_ERROR(mcap::ParseSchema(record, &schema).Prefixed(where));
      schema.name = ros2::NormalisedType(schema.name);
      if (schema.id != 0) schemas_[schema.id] = std::move(schema);
      return Status::Ok();
    }
    case mcap::kChannel:
      return OnChannel(record).Prefixed(where);
    case mcap::kMessage:
      return OnMessage(record, where);
    default:
      return Status::Ok();  // Indexes, attachments, metadata: not needed here.
  }
}

Status BagReader::OnMessage(const RecordView& record, const std::string& where) {
  mcap::MessageRecord message;
  CALIB_RETURN_IF_ERROR(mcap::ParseMessage(record, &message).Prefixed(where));
  const int64_t index = next_record_++;
  const auto channel = channels_.find(message.channel_id);
  if (channel == channels_.end()) {
    return Status::InvalidInput(where + "Message record" + At(record.offset) + " (record " +
                                std::to_string(index) + ") is on channel " +
                                std::to_string(message.channel_id) + ", never defined before it");
  }
  if (count_messages_) ++channel->second.message_count;
  if (!channel->second.wanted) return Status::Ok();
  return collector_.Decode(channel->second, message.log_time_ns, message.data, message.size, index)
      .Prefixed(where + "topic '" + channel->second.topic + "' record " + std::to_string(index) +
                " (Message record" + At(record.offset) + "): ");
}

Status BagReader::ForEachInChunk(const RecordView& record, const std::string& where) {
  const std::string chunk_where = where + "Chunk record" + At(record.offset) + ": ";
  mcap::ChunkRecord chunk;
  CALIB_RETURN_IF_ERROR(mcap::ParseChunk(record, &chunk).Prefixed(where));
  CALIB_RETURN_IF_ERROR(mcap::DecompressChunk(chunk, &chunk_buffer_).Prefixed(chunk_where));
  const std::string inner_where = chunk_where + "in its records: ";
  for (uint64_t offset = 0; offset < chunk_buffer_.size();) {
    RecordView inner;
    CALIB_RETURN_IF_ERROR(
        mcap::ReadRecordAt(chunk_buffer_.data(), chunk_buffer_.size(), offset, &inner)
            .Prefixed(inner_where));
    CALIB_RETURN_IF_ERROR(OnRecord(inner, inner_where));
    offset = inner.end();
  }
  return Status::Ok();
}

Status BagReader::ReadLinear() {
  RecordView record;
  CALIB_RETURN_IF_ERROR(mcap::ReadRecordAt(data_, size_, sizeof(mcap::kMagic), &record));
  if (record.opcode != mcap::kHeader) {
    return Status::InvalidInput("no Header record after the magic" + At(record.offset));
  }
  for (uint64_t offset = record.end();; offset = record.end()) {
    if (offset >= size_) {
      return Status::InvalidInput("truncated: the file ends" + At(size_) +
                                  " without a Footer record");
    }
    CALIB_RETURN_IF_ERROR(mcap::ReadRecordAt(data_, size_, offset, &record));
    if (record.opcode == mcap::kFooter) {
      if (size_ - record.end() >= 8 && std::memcmp(data_ + record.end(), mcap::kMagic, 8) == 0) {
        return Status::Ok();
      }
      return Status::InvalidInput("truncated or corrupt: no closing magic after the Footer record" +
                                  At(record.offset));
    }
    if (record.opcode == mcap::kChunk) {
      CALIB_RETURN_IF_ERROR(ForEachInChunk(record, ""));
    } else {
      CALIB_RETURN_IF_ERROR(OnRecord(record, ""));
    }
  }
}

// The messages of one chunk, from the sizes of its Message Index records (16 bytes an entry).
Status BagReader::CountIndexed(const ChunkIndexRecord& index, uint64_t* count, bool* known) {
  *count = 0;
  *known = !index.message_index_offsets.empty();
  for (const auto& [channel, offset] : index.message_index_offsets) {
    RecordView record;
    CALIB_RETURN_IF_ERROR(mcap::ReadRecordAt(data_, size_, offset, &record));
    if (record.opcode != mcap::kMessageIndex) {
      return Status::InvalidInput("Chunk Index of the chunk" + At(index.chunk_start_offset) +
                                  " points at byte " + std::to_string(offset) + " for channel " +
                                  std::to_string(channel) + ", not at a Message Index record");
    }
    uint64_t n = 0;
    CALIB_RETURN_IF_ERROR(mcap::CountMessageIndexEntries(record, &n));
    *count += n;
  }
  return Status::Ok();
}

// The summary section's Schema, Channel, Chunk Index and Statistics records (it ends where the
// footer begins: parsed as its own byte range).
Status BagReader::ReadSummary(const mcap::FooterRecord& footer, uint64_t footer_offset,
                              Summary* summary) {
  if (footer.summary_start < sizeof(mcap::kMagic) || footer.summary_start > footer_offset) {
    return Status::InvalidInput("Footer record" + At(footer_offset) + ": summary_start " +
                                std::to_string(footer.summary_start) + " is outside the file");
  }
  for (uint64_t offset = footer.summary_start; offset < footer_offset;) {
    RecordView record;
    CALIB_RETURN_IF_ERROR(mcap::ReadRecordAt(data_, footer_offset, offset, &record));
    if (record.opcode == mcap::kChunkIndex) {
      summary->chunks.emplace_back();
      CALIB_RETURN_IF_ERROR(mcap::ParseChunkIndex(record, &summary->chunks.back()));
    } else if (record.opcode == mcap::kStatistics) {
      CALIB_RETURN_IF_ERROR(mcap::ParseStatistics(record, &summary->statistics));
      summary->have_statistics = true;
    } else if (record.opcode == mcap::kSchema || record.opcode == mcap::kChannel) {
      CALIB_RETURN_IF_ERROR(OnRecord(record, "summary: "));
    }
    offset = record.end();
  }
  std::sort(summary->chunks.begin(), summary->chunks.end(), [](const auto& a, const auto& b) {
    return a.chunk_start_offset < b.chunk_start_offset;
  });
  return Status::Ok();
}

Status BagReader::ReadIndexed(const mcap::FooterRecord& footer, uint64_t footer_offset,
                              bool* used) {
  *used = false;
  Summary summary;
  CALIB_RETURN_IF_ERROR(ReadSummary(footer, footer_offset, &summary));
  const auto& statistics = summary.statistics;
  const auto& chunks = summary.chunks;
  if (!summary.have_statistics || statistics.channel_message_counts.empty() ||
      chunks.size() != statistics.chunk_count) {
    return Status::Ok();
  }
  std::vector<uint64_t> counts(chunks.size());
  uint64_t total = 0;
  for (size_t i = 0; i < chunks.size(); ++i) {
    bool known = false;
    CALIB_RETURN_IF_ERROR(CountIndexed(chunks[i], &counts[i], &known));
    if (!known) return Status::Ok();
    total += counts[i];
  }
  // Messages outside chunks are in no index: then record numbers need the linear scan.
  if (total != statistics.message_count) return Status::Ok();
  *used = true;
  count_messages_ = false;
  for (auto& [id, channel] : channels_) {
    const auto count = statistics.channel_message_counts.find(id);
    channel.message_count =
        count == statistics.channel_message_counts.end() ? 0 : static_cast<int64_t>(count->second);
  }
  int64_t first_record = 0;
  uint64_t read_end = 0;
  for (size_t i = 0; i < chunks.size(); first_record += counts[i++]) {
    bool wanted = false;
    for (const auto& entry : chunks[i].message_index_offsets) {
      const auto channel = channels_.find(entry.first);
      wanted = wanted || (channel != channels_.end() && channel->second.wanted);
    }
    if (!wanted) continue;
    RecordView record;
    // Each chunk is decompressed once: indexes that point into a chunk already read are corrupt
    // (and would multiply the work).
    if (chunks[i].chunk_start_offset < read_end) {
      return Status::InvalidInput(
          "Chunk Index points at byte " + std::to_string(chunks[i].chunk_start_offset) +
          ", inside a chunk already read (which ends at byte " + std::to_string(read_end) + ")");
    }
    CALIB_RETURN_IF_ERROR(mcap::ReadRecordAt(data_, size_, chunks[i].chunk_start_offset, &record));
    if (record.opcode != mcap::kChunk) {
      return Status::InvalidInput("Chunk Index points at byte " + std::to_string(record.offset) +
                                  ", not at a Chunk record");
    }
    read_end = record.end();
    next_record_ = first_record;
    CALIB_RETURN_IF_ERROR(ForEachInChunk(record, ""));
    if (next_record_ - first_record != static_cast<int64_t>(counts[i])) {
      return Status::InvalidInput("Chunk record" + At(record.offset) + " holds " +
                                  std::to_string(next_record_ - first_record) +
                                  " messages; its index says " + std::to_string(counts[i]));
    }
  }
  return Status::Ok();
}

void BagReader::Finish(RobotMessages* out) {
  for (const auto& [id, channel] : channels_) {
    out->topics.push_back({channel.topic, channel.type, channel.message_count});
  }
  collector_.Finish(out);
}

// The Footer, when the file ends with one and the closing magic.
bool FindFooter(const uint8_t* data, uint64_t size, mcap::FooterRecord* footer,
                uint64_t* footer_offset) {
  constexpr uint64_t kTail = mcap::kRecordPrefixBytes + mcap::kFooterContentBytes + 8;
  if (size < sizeof(mcap::kMagic) + kTail || std::memcmp(data + size - 8, mcap::kMagic, 8) != 0) {
    return false;
  }
  *footer_offset = size - kTail;
  RecordView record;
  return mcap::ReadRecordAt(data, size - 8, *footer_offset, &record).ok() &&
         record.opcode == mcap::kFooter && record.length == mcap::kFooterContentBytes &&
         mcap::ParseFooter(record, footer).ok();
}

}  // namespace

namespace {

StatusOr<RobotMessages> ReadMcap(const uint8_t* data, uint64_t size, const std::string& file,
                                 const BagReadOptions& options) {
  if (size < sizeof(mcap::kMagic) || std::memcmp(data, mcap::kMagic, sizeof(mcap::kMagic)) != 0) {
    return Status::InvalidInput(file + ": not an MCAP file (bad magic at byte 0)");
  }
  const std::string where = file + ": ";
  BagReader reader(data, size, options);
  mcap::FooterRecord footer;
  uint64_t footer_offset = 0;
  bool indexed = false;
  if (FindFooter(data, size, &footer, &footer_offset) && footer.summary_start != 0) {
    CALIB_RETURN_IF_ERROR(reader.ReadIndexed(footer, footer_offset, &indexed).Prefixed(where));
  }
  if (!indexed) CALIB_RETURN_IF_ERROR(reader.ReadLinear().Prefixed(where));
  RobotMessages messages;
  messages.source = file;
  reader.Finish(&messages);
  return messages;
}

StatusOr<RobotMessages> ReadMcapFile(const std::string& file, const BagReadOptions& options) {
  CALIB_ASSIGN_OR_RETURN(const MappedFile mapped, MappedFile::Open(file));
  return GuardAllocation(file,
                         [&] { return ReadMcap(mapped.data(), mapped.size(), file, options); });
}

}  // namespace

StatusOr<RobotMessages> ReadMcapBytes(std::string_view bytes, const std::string& source,
                                      const BagReadOptions& options) {
  return GuardAllocation(source, [&] {
    return ReadMcap(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(), source, options);
  });
}

StatusOr<RobotMessages> ReadMcapBag(const std::string& path, const BagReadOptions& options) {
  std::error_code error;
  if (!std::filesystem::is_directory(path, error)) return ReadMcapFile(path, options);
  CALIB_ASSIGN_OR_RETURN(const std::vector<std::string> files,
                         ros2::BagDirectoryFiles(path, ".mcap"));
  if (files.size() == 1) return ReadMcapFile(files[0], options);
  return GuardAllocation(path, [&] {
    return ros2::ReadSplitBag(path, files,
                              [&](const std::string& file) { return ReadMcapFile(file, options); });
  });
}

}  // namespace calib
