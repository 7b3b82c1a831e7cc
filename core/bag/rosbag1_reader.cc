#include <calib/core/bag/encoder_messages.h>
#include <calib/core/bag/robot_messages.h>
#include <calib/core/bag/ros1_decoder.h>
#include <calib/core/bag/rosbag1_records.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <utility>

// ReadRos1Bag: the bag header, then either the index (connection records and chunk infos after
// index_pos: topics, counts and where the chunks are, so that chunks holding no wanted topic are
// skipped) or, for a bag whose recording was interrupted (index_pos 0), a linear scan of every
// record. Each chunk is decompressed and its connection and message records walked in order.
namespace calib {
namespace {

using rosbag1::Record;

// kRaw: kept as bytes (RobotMessages::raw).
enum class Kind { kSkip, kScan, kJointState, kOdometry, kTf, kTfStatic, kRaw };

struct Connection {
  std::string topic, type;
  std::string definition;  // For kRaw: the connection's message_definition.
  Kind kind = Kind::kSkip;
  int64_t count = 0;
};

struct ChunkInfo {
  uint64_t pos = 0;
  std::vector<std::pair<uint32_t, uint32_t>> counts;  // (conn, messages in the chunk)
};

struct KnownType {
  const char* type;
  const char* md5sum;
  Kind kind;
};
constexpr KnownType kKnownTypes[] = {
    {"sensor_msgs/LaserScan", "90c7ef2dc6895d81024acba2ac42f369", Kind::kScan},
    {"sensor_msgs/JointState", "3066dcd76a6cfaef579bd0f34173e9fd", Kind::kJointState},
    {"nav_msgs/Odometry", "cd5e73d190d741a2f92e81eda573aca7", Kind::kOdometry},
    {"tf2_msgs/TFMessage", "94810edda583a504dfda3829e70d7eec", Kind::kTf},
};

std::string Hex(uint8_t op) {
  char s[8];
  std::snprintf(s, sizeof(s), "0x%02x", op);
  return s;
}

template <typename T>
void SortByLogTime(std::vector<T>* v) {
  std::stable_sort(v->begin(), v->end(),
                   [](const T& a, const T& b) { return a.log_time_s < b.log_time_s; });
}

class Ros1BagReader {
 public:
  Ros1BagReader(const std::string& path, const BagReadOptions& options)
      : path_(path), options_(options) {
    out_.source = path;
  }

  // Reads `bytes` instead of the file at the path (which only names them).
  void UseBytes(std::string_view bytes) {
    in_memory_ = true;
    file_.OpenBytes(bytes);
  }

  StatusOr<RobotMessages> Read() {
    const Status status = GuardAllocation(path_, [&] { return ReadAll(); });
    if (!status.ok()) return status.Prefixed(path_ + ": ");
    Finish();
    return std::move(out_);
  }

 private:
  Status ReadAll() {
    if (!in_memory_) CALIB_RETURN_IF_ERROR(file_.Open(path_));
    uint64_t index_pos = 0, first_record = 0;
    uint32_t conn_count = 0, chunk_count = 0;
    CALIB_RETURN_IF_ERROR(ReadBagHeader(&index_pos, &conn_count, &chunk_count, &first_record));
    if (index_pos == 0) {
      counting_ = true;  // No index: count the messages while scanning.
      return ScanLinear(first_record);
    }
    CALIB_RETURN_IF_ERROR(ReadIndex(index_pos, first_record, conn_count, chunk_count));
    return ReadIndexedChunks();
  }

  Status ReadBagHeader(uint64_t* index_pos, uint32_t* conn_count, uint32_t* chunk_count,
                       uint64_t* first_record) {
    const std::string_view magic = rosbag1::kMagic;
    if (file_.size() < magic.size()) {
      return Status::InvalidInput("not a ROS bag: " + std::to_string(file_.size()) +
                                  " bytes, too short for the line '#ROSBAG V2.0'");
    }
    std::string start;
    CALIB_RETURN_IF_ERROR(file_.ReadAt(0, magic.size(), &start));
    if (start != magic) {
      if (start.rfind("#ROSBAG V", 0) == 0 || start.rfind("#ROSRECORD V", 0) == 0) {
        std::string line;  // "#ROSRECORD V1.2" is longer than the 2.0 magic.
        CALIB_RETURN_IF_ERROR(file_.ReadAt(0, std::min<uint64_t>(file_.size(), 24), &line));
        const std::string version = line.substr(line.find('V') + 1);
        return Status::InvalidInput("unsupported ROS bag version '" +
                                    version.substr(0, version.find('\n')) +
                                    "': this reader reads version 2.0 (ROS's `rosbag fix` "
                                    "rewrites an older bag as 2.0)");
      }
      return Status::InvalidInput("not a ROS bag: it does not start with '#ROSBAG V2.0'");
    }
    uint64_t pos = magic.size();
    CALIB_RETURN_IF_ERROR(file_.ReadRecord(&pos, false, &buffer_, &record_));
    const std::string where = "bag header record at byte " + std::to_string(magic.size()) + ": ";
    if (record_.op != rosbag1::kOpBagHeader) {
      return Status::InvalidInput(where + "op " + Hex(record_.op) + ", expected 0x03");
    }
    Status status = Load(record_.header.U64("index_pos"), index_pos);
    if (status.ok()) status = Load(record_.header.U32("conn_count"), conn_count);
    if (status.ok()) status = Load(record_.header.U32("chunk_count"), chunk_count);
    if (!status.ok()) return status.Prefixed(where);
    *first_record = pos;
    if (*index_pos != 0 && (*index_pos < pos || *index_pos > file_.size())) {
      return Status::InvalidInput(where + "truncated or corrupt: the index at byte " +
                                  std::to_string(*index_pos) + " lies outside the file's " +
                                  std::to_string(file_.size()) + " bytes after the header");
    }
    return Status::Ok();
  }

  template <typename T>
  static Status Load(StatusOr<T> value, T* out) {
    if (!value.ok()) return value.status();
    *out = *value;
    return Status::Ok();
  }

  Status ReadIndex(uint64_t index_pos, uint64_t first_record, uint32_t conn_count,
                   uint32_t chunk_count) {
    uint64_t pos = index_pos;
    reading_index_ = true;
    while (pos < file_.size()) {
      const uint64_t at = pos;
      CALIB_RETURN_IF_ERROR(file_.ReadRecord(&pos, true, &buffer_, &record_)
                                .Prefixed("index at byte " + std::to_string(index_pos) + ": "));
      const std::string where = "index record at byte " + std::to_string(at) + ": ";
      Status status;
      if (record_.op == rosbag1::kOpConnection) {
        status = AddConnection(record_);
      } else if (record_.op == rosbag1::kOpChunkInfo) {
        status = AddChunkInfo(record_, first_record, index_pos);
      } else {
        status = Status::InvalidInput("op " + Hex(record_.op) +
                                      ", expected a connection (0x07) or chunk info (0x06)");
      }
      if (!status.ok()) return status.Prefixed(where);
    }
    reading_index_ = false;
    if (index_connections_ != conn_count || chunks_.size() != chunk_count) {
      return Status::InvalidInput(
          "truncated or corrupt index at byte " + std::to_string(index_pos) + ": it holds " +
          std::to_string(index_connections_) + " connections and " +
          std::to_string(chunks_.size()) + " chunk infos, the bag header states " +
          std::to_string(conn_count) + " and " + std::to_string(chunk_count));
    }
    return Status::Ok();
  }

  Status AddChunkInfo(const Record& record, uint64_t first_record, uint64_t index_pos) {
    uint32_t version = 0, count = 0;
    ChunkInfo info;
    CALIB_RETURN_IF_ERROR(Load(record.header.U32("ver"), &version));
    CALIB_RETURN_IF_ERROR(Load(record.header.U64("chunk_pos"), &info.pos));
    CALIB_RETURN_IF_ERROR(Load(record.header.U32("count"), &count));
    if (version != 1) {
      return Status::InvalidInput("chunk info version " + std::to_string(version) + ", not 1");
    }
    if (record.data.size() != uint64_t{count} * 8) {
      return Status::InvalidInput("chunk info of " + std::to_string(count) + " connections has " +
                                  std::to_string(record.data.size()) + " bytes of data, not " +
                                  std::to_string(uint64_t{count} * 8));
    }
    if (info.pos < first_record || info.pos >= index_pos) {
      return Status::InvalidInput("chunk info points at byte " + std::to_string(info.pos) +
                                  ", outside the chunks' bytes [" + std::to_string(first_record) +
                                  ", " + std::to_string(index_pos) + ")");
    }
    for (uint32_t i = 0; i < count; ++i) {
      const char* p = record.data.data() + 8 * i;
      const uint32_t conn = rosbag1::LoadU32(p), messages = rosbag1::LoadU32(p + 4);
      const auto it = connections_.find(conn);
      if (it == connections_.end()) {
        return Status::InvalidInput("chunk info names connection " + std::to_string(conn) +
                                    ", which the index does not define before it");
      }
      it->second.count += messages;
      info.counts.emplace_back(conn, messages);
    }
    chunks_.push_back(std::move(info));
    return Status::Ok();
  }

  Status ReadIndexedChunks() {
    std::stable_sort(chunks_.begin(), chunks_.end(),
                     [](const ChunkInfo& a, const ChunkInfo& b) { return a.pos < b.pos; });
    uint64_t read_end = 0;
    for (const ChunkInfo& info : chunks_) {
      int64_t messages = 0;
      bool wanted = false;
      for (const auto& [conn, count] : info.counts) {
        messages += count;
        wanted = wanted || connections_.at(conn).kind != Kind::kSkip;
      }
      if (!wanted) {  // Nothing to decode: skip the chunk, keeping the messages' numbering.
        next_record_ += messages;
        continue;
      }
      uint64_t pos = info.pos;
      // Each chunk is read once: a chunk info pointing into one already read is corrupt (and
      // would multiply the work).
      if (info.pos < read_end) {
        return Status::InvalidInput("a chunk info points at byte " + std::to_string(info.pos) +
                                    ", inside a chunk already read (which ends at byte " +
                                    std::to_string(read_end) + ")");
      }
      CALIB_RETURN_IF_ERROR(file_.ReadRecord(&pos, true, &buffer_, &record_));
      read_end = pos;
      if (record_.op != rosbag1::kOpChunk) {
        return Status::InvalidInput("a chunk info points at byte " + std::to_string(info.pos) +
                                    ", which holds op " + Hex(record_.op) + ", not a chunk");
      }
      const int64_t before = next_record_;
      CALIB_RETURN_IF_ERROR(ReadChunk(info.pos, record_));
      if (next_record_ - before != messages) {
        return Status::InvalidInput("chunk at byte " + std::to_string(info.pos) + " holds " +
                                    std::to_string(next_record_ - before) +
                                    " messages, its chunk info states " + std::to_string(messages));
      }
    }
    return Status::Ok();
  }

  Status ScanLinear(uint64_t pos) {
    while (pos < file_.size()) {
      const uint64_t at = pos;
      // Read only the header first: index data need no reading.
      CALIB_RETURN_IF_ERROR(file_.ReadRecord(&pos, false, &buffer_, &record_));
      const uint8_t op = record_.op;
      if (op == rosbag1::kOpIndexData || op == rosbag1::kOpChunkInfo) continue;
      uint64_t again = at;
      CALIB_RETURN_IF_ERROR(file_.ReadRecord(&again, true, &buffer_, &record_));
      const std::string where = "record at byte " + std::to_string(at) + ": ";
      Status status;
      if (op == rosbag1::kOpChunk) {
        status = ReadChunk(at, record_);
      } else if (op == rosbag1::kOpConnection) {
        status = AddConnection(record_).Prefixed(where);
      } else if (op == rosbag1::kOpMessageData) {
        status = AddMessage(record_, where);
      } else {
        status = Status::InvalidInput(where + "unexpected op " + Hex(op));
      }
      CALIB_RETURN_IF_ERROR(status);
    }
    return Status::Ok();
  }

  // A chunk's data: its connection and message records, decompressed.
  Status ReadChunk(uint64_t chunk_pos, const Record& chunk) {
    const std::string where = "chunk at byte " + std::to_string(chunk_pos) + ": ";
    std::string_view compression = "none";
    if (chunk.header.Has("compression")) compression = *chunk.header.Bytes("compression");
    uint32_t size = static_cast<uint32_t>(chunk.data.size());
    if (chunk.header.Has("size") || compression != "none") {
      CALIB_RETURN_IF_ERROR(Load(chunk.header.U32("size"), &size).Prefixed(where));
    }
    std::string_view data = chunk.data;
    if (compression != "none" || size != data.size()) {
      const Status status = rosbag1::DecompressChunk(compression, chunk.data, size, &chunk_data_);
      if (!status.ok()) return status.Prefixed(where);
      data = chunk_data_;
    }
    const std::string inner = where + "(decompressed data) ";
    uint64_t pos = 0;
    Record record;
    while (pos < data.size()) {
      CALIB_RETURN_IF_ERROR(rosbag1::ParseRecord(data, 0, &pos, &record).Prefixed(inner));
      if (record.op == rosbag1::kOpMessageData) {
        CALIB_RETURN_IF_ERROR(AddMessage(record, where));
      } else if (record.op == rosbag1::kOpConnection) {
        CALIB_RETURN_IF_ERROR(AddConnection(record).Prefixed(inner));
      } else {
        return Status::InvalidInput(inner + "op " + Hex(record.op) + " inside a chunk");
      }
    }
    return Status::Ok();
  }

  Status AddConnection(const Record& record) {
    uint32_t id = 0;
    CALIB_RETURN_IF_ERROR(Load(record.header.U32("conn"), &id));
    CALIB_ASSIGN_OR_RETURN(std::string_view topic, record.header.Bytes("topic"));
    auto fields = rosbag1::FieldList::Parse(record.data);
    if (!fields.ok()) return fields.status().Prefixed("connection data: ");
    if (reading_index_) ++index_connections_;
    if (connections_.count(id)) return Status::Ok();  // Both in its chunk and in the index.
    Connection c;
    c.topic = std::string(topic);
    std::string_view type, md5sum;
    CALIB_RETURN_IF_ERROR(Load(fields->Bytes("type"), &type).Prefixed("connection data: "));
    CALIB_RETURN_IF_ERROR(Load(fields->Bytes("md5sum"), &md5sum).Prefixed("connection data: "));
    c.type = std::string(type);
    if (options_.topics.empty() || options_.topics.count(c.topic)) {
      for (const KnownType& known : kKnownTypes) {
        if (type != known.type) continue;
        if (md5sum != known.md5sum && md5sum != "*") {
          return Status::InvalidInput("topic '" + c.topic + "': type " + c.type + " with md5sum " +
                                      std::string(md5sum) + ", not the definition read here (" +
                                      known.md5sum + ")");
        }
        c.kind = known.kind;
        const std::string_view name = c.topic;
        const std::string_view suffix = "tf_static";
        if (c.kind == Kind::kTf && name.size() >= suffix.size() &&
            name.substr(name.size() - suffix.size()) == suffix) {
          c.kind = Kind::kTfStatic;
        }
      }
      if (c.kind == Kind::kSkip &&
          (FindEncoderMessageType(c.type) != nullptr || options_.raw_topics.count(c.topic) > 0)) {
        c.kind = Kind::kRaw;
        std::string_view definition;
        if (fields->Bytes("message_definition").ok()) {
          CALIB_RETURN_IF_ERROR(Load(fields->Bytes("message_definition"), &definition));
        }
        c.definition = std::string(definition);
      }
    }
    connections_.emplace(id, std::move(c));
    return Status::Ok();
  }

  Status AddMessage(const Record& record, const std::string& where) {
    const int64_t index = next_record_++;
    uint32_t id = 0;
    rosbag1::Time time;
    Status status = Load(record.header.U32("conn"), &id);
    if (status.ok()) status = Load(record.header.TimeField("time"), &time);
    if (!status.ok()) return status.Prefixed(where + "message " + std::to_string(index) + ": ");
    const auto it = connections_.find(id);
    if (it == connections_.end()) {
      return Status::InvalidInput(where + "message " + std::to_string(index) +
                                  " names connection " + std::to_string(id) +
                                  ", which no connection record defines before it");
    }
    Connection& c = it->second;
    if (counting_) ++c.count;
    status = Decode(c, record.data, time.Seconds(), index);
    if (!status.ok()) {
      return status.Prefixed(where + "topic '" + c.topic + "', message " + std::to_string(index) +
                             ": ");
    }
    return Status::Ok();
  }

  template <typename T>
  static void Stamp(T* msg, double log_time_s, int64_t index) {
    msg->log_time_s = log_time_s;
    msg->record = index;
  }

  Status Decode(const Connection& c, std::string_view bytes, double log_time_s, int64_t index) {
    switch (c.kind) {
      case Kind::kSkip:
        return Status::Ok();
      case Kind::kScan: {
        LaserScan scan;
        CALIB_RETURN_IF_ERROR(ros1::DecodeLaserScan(bytes, &scan));
        Stamp(&scan, log_time_s, index);
        out_.scans[c.topic].push_back(std::move(scan));
        return Status::Ok();
      }
      case Kind::kJointState: {
        JointState joints;
        CALIB_RETURN_IF_ERROR(ros1::DecodeJointState(bytes, &joints));
        Stamp(&joints, log_time_s, index);
        out_.joint_states[c.topic].push_back(std::move(joints));
        return Status::Ok();
      }
      case Kind::kOdometry: {
        Odometry odometry;
        CALIB_RETURN_IF_ERROR(ros1::DecodeOdometry(bytes, &odometry));
        Stamp(&odometry, log_time_s, index);
        out_.odometry[c.topic].push_back(std::move(odometry));
        return Status::Ok();
      }
      case Kind::kTf:
      case Kind::kTfStatic: {
        std::vector<TransformStamped>* tf = c.kind == Kind::kTf ? &out_.tf : &out_.tf_static;
        const size_t first = tf->size();
        CALIB_RETURN_IF_ERROR(ros1::DecodeTfMessage(bytes, tf));
        for (size_t i = first; i < tf->size(); ++i) Stamp(&(*tf)[i], log_time_s, index);
        return Status::Ok();
      }
      case Kind::kRaw: {
        RawTopic& raw = out_.raw[c.topic];
        if (raw.messages.empty()) raw = RawTopic{c.type, c.definition, false, {}};
        raw.messages.push_back(
            RawMessage{log_time_s, index, std::vector<uint8_t>(bytes.begin(), bytes.end())});
        return Status::Ok();
      }
    }
    return Status::Internal("unhandled message kind");
  }

  void Finish() {
    std::map<std::string, TopicInfo> topics;
    for (const auto& [id, c] : connections_) {
      TopicInfo& info = topics[c.topic];
      if (info.name.empty()) info = {c.topic, c.type, 0};
      info.message_count += c.count;
    }
    for (auto& [name, info] : topics) out_.topics.push_back(std::move(info));
    for (auto& [topic, v] : out_.scans) SortByLogTime(&v);
    for (auto& [topic, v] : out_.joint_states) SortByLogTime(&v);
    for (auto& [topic, v] : out_.odometry) SortByLogTime(&v);
    for (auto& [topic, raw] : out_.raw) SortByLogTime(&raw.messages);
    SortByLogTime(&out_.tf);
    SortByLogTime(&out_.tf_static);
  }

  std::string path_;
  BagReadOptions options_;
  rosbag1::BagFile file_;
  std::map<uint32_t, Connection> connections_;
  std::vector<ChunkInfo> chunks_;
  uint32_t index_connections_ = 0;
  bool counting_ = false, reading_index_ = false, in_memory_ = false;
  int64_t next_record_ = 0;  // Every message's index in the bag, in file order.
  std::string buffer_, chunk_data_;
  Record record_;
  RobotMessages out_;
};

}  // namespace

StatusOr<RobotMessages> ReadRos1Bag(const std::string& path, const BagReadOptions& options) {
  return Ros1BagReader(path, options).Read();
}

StatusOr<RobotMessages> ReadRos1BagBytes(std::string_view bytes, const std::string& source,
                                         const BagReadOptions& options) {
  Ros1BagReader reader(source, options);
  reader.UseBytes(bytes);
  return reader.Read();
}

}  // namespace calib
