// ReadSqliteBag: a ROS 2 bag in rosbag2's sqlite3 storage (.db3 files, the default before Iron),
// read through SQLite's C API: the topics and messages tables, CDR messages, zstd-compressed per
// message or per file.
#include <calib/core/bag/robot_messages.h>
#include <calib/core/bag/ros2_collector.h>
#include <calib/core/text_file.h>
#include <sqlite3.h>
#include <zstd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <utility>

namespace calib {
namespace {

namespace fs = std::filesystem;

constexpr uint8_t kZstdMagic[4] = {0x28, 0xb5, 0x2f, 0xfd};
constexpr char kFileSuffix[] = ".db3";
constexpr char kCompressedSuffix[] = ".db3.zstd";

bool IsZstd(const uint8_t* data, size_t size) {
  return size >= sizeof(kZstdMagic) && std::memcmp(data, kZstdMagic, sizeof(kZstdMagic)) == 0;
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// A zstd stream's content (one frame or several, its size given or not).
Status DecompressZstd(const uint8_t* data, size_t size, std::vector<uint8_t>* out) {
  const unsigned long long framed = ZSTD_getFrameContentSize(data, size);
  if (framed == ZSTD_CONTENTSIZE_ERROR) return Status::InvalidInput("zstd data corrupt");
  std::unique_ptr<ZSTD_DStream, size_t (*)(ZSTD_DStream*)> stream(ZSTD_createDStream(),
                                                                  ZSTD_freeDStream);
  if (!stream) throw std::bad_alloc();
  // The frame's stated size sizes the buffer only up to a bound, so that a corrupt header cannot
  // make it allocate more than the stream holds.
  const size_t guess = 64 * size + 4096;
  out->resize(framed != ZSTD_CONTENTSIZE_UNKNOWN && framed < guess ? static_cast<size_t>(framed) + 1
                                                                   : guess);
  ZSTD_inBuffer in{data, size, 0};
  ZSTD_outBuffer to{out->data(), out->size(), 0};
  size_t left = 1;
  while (in.pos < in.size || left != 0) {
    if (to.pos == to.size) {
      out->resize(2 * out->size());
      to.dst = out->data();
      to.size = out->size();
    }
    const size_t before = in.pos + to.pos;
    left = ZSTD_decompressStream(stream.get(), &to, &in);
    if (ZSTD_isError(left)) {
      return Status::InvalidInput(std::string("zstd data corrupt: ") + ZSTD_getErrorName(left));
    }
    if (in.pos == in.size && left != 0 && in.pos + to.pos == before) {
      return Status::InvalidInput("zstd data truncated: the stream ends inside a frame");
    }
  }
  out->resize(to.pos);
  return Status::Ok();
}

using DatabasePtr = std::unique_ptr<sqlite3, int (*)(sqlite3*)>;
using StatementPtr = std::unique_ptr<sqlite3_stmt, int (*)(sqlite3_stmt*)>;

// One database, read-only: a file, or a decompressed file's bytes (kept alive by `bytes`).
struct Database {
  DatabasePtr db{nullptr, sqlite3_close};
  std::vector<uint8_t> bytes;
  std::string file;

  Status Error(const std::string& doing) const {
    return Status::InvalidInput(file + ": " + doing + ": SQLite says: " + sqlite3_errmsg(db.get()) +
                                " (a truncated or corrupt .db3 file, or not a rosbag2 database)");
  }
  StatusOr<StatementPtr> Prepare(const std::string& sql, const std::string& doing) const {
    sqlite3_stmt* statement = nullptr;
    if (sqlite3_prepare_v2(db.get(), sql.c_str(), -1, &statement, nullptr) != SQLITE_OK) {
      sqlite3_finalize(statement);
      return Error(doing);
    }
    return StatementPtr(statement, sqlite3_finalize);
  }
};

// Checks the pages as they are read, and refuses what a crafted file could make SQLite do.
void Harden(sqlite3* db) {
  sqlite3_db_config(db, SQLITE_DBCONFIG_DEFENSIVE, 1, nullptr);
  sqlite3_exec(db, "PRAGMA cell_size_check = ON", nullptr, nullptr, nullptr);
}

// A database over `bytes` (a decompressed file, or bytes given in memory), read-only.
StatusOr<Database> DatabaseFromBytes(std::vector<uint8_t> bytes, const std::string& file) {
  Database database;
  database.file = file;
  database.bytes = std::move(bytes);
  sqlite3* db = nullptr;
  int opened = sqlite3_open_v2(":memory:", &db, SQLITE_OPEN_READWRITE, nullptr);
  database.db.reset(db);
  if (opened == SQLITE_OK) {
    opened = sqlite3_deserialize(
        db, "main", database.bytes.data(), static_cast<sqlite3_int64>(database.bytes.size()),
        static_cast<sqlite3_int64>(database.bytes.size()), SQLITE_DESERIALIZE_READONLY);
  }
  if (opened != SQLITE_OK) {
    if (!database.db) throw std::bad_alloc();
    return database.Error("cannot open it");
  }
  Harden(db);
  return database;
}

StatusOr<Database> OpenDatabase(const std::string& file) {
  std::error_code error;
  if (!fs::exists(file, error)) return Status::Io(file + ": no such file or directory");
  if (!fs::is_regular_file(file, error)) return Status::Io(file + ": not a regular file");
  if (EndsWith(file, kCompressedSuffix)) {  // rosbag2's compression_mode FILE.
    CALIB_ASSIGN_OR_RETURN(const MappedFile mapped, MappedFile::Open(file));
    if (!IsZstd(mapped.data(), mapped.size())) {
      return Status::InvalidInput(file + ": named .db3.zstd but not zstd data (bad magic)");
    }
    std::vector<uint8_t> bytes;
    CALIB_RETURN_IF_ERROR(
        DecompressZstd(mapped.data(), mapped.size(), &bytes).Prefixed(file + ": "));
    return DatabaseFromBytes(std::move(bytes), file);
  }
  Database database;
  database.file = file;
  sqlite3* db = nullptr;
  const int opened = sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READONLY, nullptr);
  database.db.reset(db);
  if (opened != SQLITE_OK) {
    if (!database.db) throw std::bad_alloc();
    return database.Error("cannot open it");
  }
  Harden(db);
  return database;
}

// The columns each table must have (older rosbag2 versions lack others, which are not read).
Status CheckSchema(const Database& database) {
  CALIB_ASSIGN_OR_RETURN(StatementPtr tables,
                         database.Prepare("SELECT name FROM sqlite_master WHERE type = 'table'",
                                          "reading its tables"));
  std::vector<std::string> names;
  int step = SQLITE_ROW;
  while ((step = sqlite3_step(tables.get())) == SQLITE_ROW) {
    names.emplace_back(reinterpret_cast<const char*>(sqlite3_column_text(tables.get(), 0)));
  }
  if (step != SQLITE_DONE) return database.Error("reading its tables");
  for (const char* needed : {"topics", "messages"}) {
    if (std::find(names.begin(), names.end(), needed) != names.end()) continue;
    std::string listed;
    for (const std::string& n : names) listed += (listed.empty() ? "" : ", ") + n;
    return Status::InvalidInput(database.file + ": not a rosbag2 database: it has no '" + needed +
                                "' table (its tables: " + (listed.empty() ? "none" : listed) + ")");
  }
  return Status::Ok();
}

std::string Text(sqlite3_stmt* statement, int column) {
  const unsigned char* text = sqlite3_column_text(statement, column);
  return text == nullptr ? std::string() : reinterpret_cast<const char*>(text);
}

// The message definitions the bag stores by type (rosbag2 from Jazzy on; none before).
std::map<std::string, std::string> ReadDefinitions(const Database& database) {
  std::map<std::string, std::string> definitions;
  sqlite3_stmt* raw = nullptr;
  if (sqlite3_prepare_v2(database.db.get(),
                         "SELECT topic_type, encoded_message_definition FROM message_definitions "
                         "WHERE encoding = 'ros2msg'",
                         -1, &raw, nullptr) != SQLITE_OK) {
    sqlite3_finalize(raw);
    return definitions;  // No such table.
  }
  const StatementPtr statement(raw, sqlite3_finalize);
  while (sqlite3_step(raw) == SQLITE_ROW) {
    definitions[ros2::NormalisedType(Text(raw, 0))] = Text(raw, 1);
  }
  return definitions;
}

// The topics by id, each with its message count.
StatusOr<std::map<int64_t, ros2::Channel>> ReadTopics(const Database& database,
                                                      const BagReadOptions& options) {
  const std::map<std::string, std::string> definitions = ReadDefinitions(database);
  std::map<int64_t, ros2::Channel> channels;
  CALIB_ASSIGN_OR_RETURN(
      StatementPtr topics,
      database.Prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id",
                       "reading the topics table"));
  int step = SQLITE_ROW;
  while ((step = sqlite3_step(topics.get())) == SQLITE_ROW) {
    const std::string type = ros2::NormalisedType(Text(topics.get(), 2));
    const auto definition = definitions.find(type);
    channels[sqlite3_column_int64(topics.get(), 0)] =
        ros2::MakeChannel(Text(topics.get(), 1), type, Text(topics.get(), 3), options,
                          definition == definitions.end() ? "" : definition->second);
  }
  if (step != SQLITE_DONE) return database.Error("reading the topics table");
  CALIB_ASSIGN_OR_RETURN(
      StatementPtr counts,
      database.Prepare("SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id",
                       "counting the messages"));
  while ((step = sqlite3_step(counts.get())) == SQLITE_ROW) {
    const int64_t id = sqlite3_column_int64(counts.get(), 0);
    const auto channel = channels.find(id);
    if (channel == channels.end()) {
      return Status::InvalidInput(database.file + ": " +
                                  std::to_string(sqlite3_column_int64(counts.get(), 1)) +
                                  " messages are on topic id " + std::to_string(id) +
                                  ", which the topics table does not define");
    }
    channel->second.message_count = sqlite3_column_int64(counts.get(), 1);
  }
  if (step != SQLITE_DONE) return database.Error("counting the messages");
  return channels;
}

// The wanted topics' messages, in (timestamp, id) order as rosbag2 plays them. Records count
// from 0 in the order rosbag2 wrote them (id − 1: its ids count from 1); errors name the id.
Status ReadMessages(const Database& database, const std::map<int64_t, ros2::Channel>& channels,
                    ros2::MessageCollector* collector) {
  std::string ids;
  for (const auto& [id, channel] : channels) {
    if (channel.wanted) ids += (ids.empty() ? "" : ",") + std::to_string(id);
  }
  if (ids.empty()) return Status::Ok();
  const std::string doing = "reading the messages table";
  CALIB_ASSIGN_OR_RETURN(StatementPtr messages,
                         database.Prepare("SELECT id, topic_id, timestamp, data FROM messages "
                                          "WHERE topic_id IN (" +
                                              ids + ") ORDER BY timestamp, id",
                                          doing));
  std::vector<uint8_t> decompressed;
  int step = SQLITE_ROW;
  while ((step = sqlite3_step(messages.get())) == SQLITE_ROW) {
    const int64_t id = sqlite3_column_int64(messages.get(), 0);
    const ros2::Channel& channel = channels.at(sqlite3_column_int64(messages.get(), 1));
    const int64_t timestamp = sqlite3_column_int64(messages.get(), 2);
    const auto* data = static_cast<const uint8_t*>(sqlite3_column_blob(messages.get(), 3));
    size_t size = static_cast<size_t>(sqlite3_column_bytes(messages.get(), 3));
    const std::string where =
        database.file + ": topic '" + channel.topic + "' message id " + std::to_string(id) + ": ";
    if (timestamp < 0) {
      return Status::InvalidInput(where + "negative timestamp " + std::to_string(timestamp));
    }
    if (IsZstd(data, size)) {  // rosbag2's compression_mode MESSAGE.
      CALIB_RETURN_IF_ERROR(DecompressZstd(data, size, &decompressed).Prefixed(where));
      data = decompressed.data();
      size = decompressed.size();
    }
    CALIB_RETURN_IF_ERROR(
        collector->Decode(channel, static_cast<uint64_t>(timestamp), data, size, id - 1)
            .Prefixed(where));
  }
  if (step != SQLITE_DONE) return database.Error(doing);
  return Status::Ok();
}

StatusOr<RobotMessages> ReadDatabase(const Database& database, const BagReadOptions& options) {
  CALIB_RETURN_IF_ERROR(CheckSchema(database));
  CALIB_ASSIGN_OR_RETURN(const auto channels, ReadTopics(database, options));
  ros2::MessageCollector collector;
  CALIB_RETURN_IF_ERROR(ReadMessages(database, channels, &collector));
  RobotMessages messages;
  messages.source = database.file;
  for (const auto& [id, channel] : channels) {
    messages.topics.push_back({channel.topic, channel.type, channel.message_count});
  }
  collector.Finish(&messages);
  return messages;
}

StatusOr<RobotMessages> ReadSqliteFile(const std::string& file, const BagReadOptions& options) {
  CALIB_ASSIGN_OR_RETURN(const Database database, OpenDatabase(file));
  return ReadDatabase(database, options);
}

// metadata.yaml's `key: value` (first occurrence, quotes removed); empty when absent.
std::string MetadataValue(const std::string& text, const std::string& key) {
  for (size_t at = text.find(key + ":"); at != std::string::npos;
       at = text.find(key + ":", at + 1)) {
    if (at > 0 && text[at - 1] != ' ' && text[at - 1] != '\n') continue;
    const size_t begin = at + key.size() + 1, end = text.find('\n', begin);
    std::string value = text.substr(begin, end == std::string::npos ? end : end - begin);
    value.erase(0, value.find_first_not_of(" \t"));
    value.erase(value.find_last_not_of(" \t\r") + 1);
    if (value.size() >= 2 && (value.front() == '"' || value.front() == '\'')) {
      value = value.substr(1, value.size() - 2);
    }
    return value;
  }
  return "";
}

// Refuses a compression this reader cannot undo (rosbag2 writes zstd only, but plugins exist).
Status CheckCompression(const std::string& directory) {
  std::ifstream in(fs::path(directory) / "metadata.yaml");
  if (!in) return Status::Ok();
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string format = MetadataValue(text, "compression_format");
  if (format.empty() || format == "zstd") return Status::Ok();
  return Status::InvalidInput(directory + "/metadata.yaml: compression_format '" + format +
                              "' (compression_mode '" + MetadataValue(text, "compression_mode") +
                              "'): calib reads rosbag2's zstd compression only; decompress the "
                              "bag first (ros2 bag convert)");
}

}  // namespace

bool HoldsSqliteBag(const std::string& directory) {
  std::error_code error;
  for (const auto& entry : fs::directory_iterator(directory, error)) {
    const std::string name = entry.path().filename().string();
    if (EndsWith(name, kFileSuffix) || EndsWith(name, kCompressedSuffix)) return true;
  }
  return false;
}

StatusOr<RobotMessages> ReadSqliteBag(const std::string& path, const BagReadOptions& options) {
  std::error_code error;
  if (!fs::is_directory(path, error)) {
    return GuardAllocation(path, [&] { return ReadSqliteFile(path, options); });
  }
  CALIB_RETURN_IF_ERROR(CheckCompression(path));
  StatusOr<std::vector<std::string>> files = ros2::BagDirectoryFiles(path, kFileSuffix);
  if (!files.ok()) files = ros2::BagDirectoryFiles(path, kCompressedSuffix);
  if (!files.ok()) {
    return Status::InvalidInput(path + ": the bag directory holds no .db3 or .db3.zstd file");
  }
  return GuardAllocation(path, [&] {
    return files->size() == 1 ? ReadSqliteFile(files->front(), options)
                              : ros2::ReadSplitBag(path, *files, [&](const std::string& file) {
                                  return ReadSqliteFile(file, options);
                                });
  });
}

StatusOr<RobotMessages> ReadSqliteBytes(std::string_view bytes, const std::string& source,
                                        const BagReadOptions& options) {
  return GuardAllocation(source, [&]() -> StatusOr<RobotMessages> {
    CALIB_ASSIGN_OR_RETURN(
        const Database database,
        DatabaseFromBytes(std::vector<uint8_t>(bytes.begin(), bytes.end()), source));
    return ReadDatabase(database, options);
  });
}

}  // namespace calib
