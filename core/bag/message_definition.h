#ifndef CALIB_CORE_BAG_MESSAGE_DEFINITION_H_
#define CALIB_CORE_BAG_MESSAGE_DEFINITION_H_

#include <calib/core/status.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

// A decoder of ROS messages of any type, driven by the message definition text a bag stores with
// each topic (rosbag1 connection records, MCAP "ros1msg"/"ros2msg" schemas, rosbag2 metadata), so
// that numeric fields of custom messages (a robot's raw wheel encoder ticks, say) can be read
// without code generated for that type.
namespace calib {

// How the messages are serialized: ROS 1 (little-endian, packed, no alignment) or ROS 2's CDR
// (XCDR1 after a 4-byte encapsulation header: 00 01 = little-endian, 00 00 = big-endian; each
// primitive aligned to min(its size, 8) counted from the end of that header).
enum class WireFormat { kRos1, kCdr };

class MessageDefinition {
 private:
  // A resolved path: the index of the field at each level, and which value it gives.
  struct Leaf {
    std::vector<uint32_t> fields;
    size_t output = 0;
  };

 public:
  // Paths resolved against one definition once, to read many messages without resolving them
  // again; only the definition that resolved them (or a copy of it) reads with them.
  class ResolvedPaths {
   public:
    // How many paths were resolved: the number of values a read gives.
    size_t size() const { return size_; }

   private:
    friend class MessageDefinition;
    uint64_t definition_id_ = 0;
    size_t size_ = 0;
    std::vector<Leaf> leaves_;  // In the order the fields come in a message.
  };

  // `type`: "pkg/Type" or "pkg/msg/Type" (normalised to "pkg/Type"); `text`: the full definition
  // as bags store it: the type's own fields, then each dependency after a line of '=' (80 of
  // them) and a line "MSG: pkg/Type" (ROS 2 bags may write "MSG: pkg/msg/Type"). Errors name the
  // type and line.
  static StatusOr<MessageDefinition> Parse(const std::string& type, const std::string& text,
                                           WireFormat format);

  const std::string& type() const;
  WireFormat format() const { return format_; }
  // Whether the first field is a std_msgs/Header (named "header").
  bool has_header() const;

  // The values of the fields at `paths` ("left_encoder", "sensor.left", "header.stamp"), each a
  // number: any integer or float type, bool, or a time/duration (ROS 1 `time`/`duration`, ROS 2
  // builtin_interfaces/Time or Duration: sec + 1e-9·nanosec, as seconds). Fields inside arrays
  // cannot be named. Walks the message once, and only up to the last field asked for: the rest of
  // the message, like trailing bytes, is not checked. Errors: a path that names no field (the
  // message lists the numeric ones), a path to a non-numeric field, a message that ends inside a
  // field ("the message's N bytes end inside field 'x'"), a count larger than the bytes left can
  // hold, an unsupported CDR encapsulation.
  StatusOr<std::vector<double>> ReadNumbers(const uint8_t* data, size_t size,
                                            const std::vector<std::string>& paths) const;
  // The same with paths resolved beforehand; `values` gets paths.size() values.
  Status ReadNumbers(const uint8_t* data, size_t size, const ResolvedPaths& paths,
                     std::vector<double>* values) const;
  // `paths` resolved for ReadNumbers, or the errors ReadNumbers gives for a path.
  StatusOr<ResolvedPaths> Resolve(const std::vector<std::string>& paths) const;

  // The primitive type name of the numeric field at `path` as it is decoded ("int32", "uint16",
  // "float64", "bool", "time", "duration", ...: ROS 1 byte is "int8", ROS 2 byte and char are
  // "uint8", builtin_interfaces/Time and Duration are "time" and "duration"), or the error
  // ReadNumbers gives for that path.
  StatusOr<std::string> FieldType(const std::string& path) const;
  // Every numeric field's path (not inside arrays), in definition order, for messages that list
  // candidates. A time is one field ("header.stamp"), not its seconds and nanoseconds.
  std::vector<std::string> NumericFields() const;

 private:
  enum class Kind : uint8_t {
    kBool,
    kInt8,
    kUint8,
    kInt16,
    kUint16,
    kInt32,
    kUint32,
    kInt64,
    kUint64,
    kFloat32,
    kFloat64,
    kTime,      // ROS 1 time: uint32 secs, uint32 nsecs.
    kDuration,  // ROS 1 duration: int32 secs, int32 nsecs.
    kString,
    kWString,
    kMessage,
  };
  enum class Array : uint8_t { kNone, kFixed, kSequence };
  struct Field {
    std::string name;
    Kind kind = Kind::kMessage;
    Array array = Array::kNone;
    uint32_t length = 0;   // Of a fixed array.
    int32_t message = -1;  // Index in types_ of a kMessage field's type.
  };
  struct Type {
    std::string name;  // "pkg/Type".
    std::vector<Field> fields;
    // kTime or kDuration for ROS 2's builtin_interfaces/Time and Duration (int32 sec, uint32
    // nanosec), read as one number; kMessage otherwise.
    Kind time = Kind::kMessage;
    size_t min_bytes = 0;  // No serialization of the type is shorter (padding aside).
    // The size of every ROS 1 serialization, or kVariable (strings, sequences, CDR).
    size_t fixed_bytes = 0;
  };
  static constexpr size_t kVariable = static_cast<size_t>(-1);
  // A primitive's bytes on the wire (a ROS 1 time or duration: 8; a string at least its 4-byte
  // length); 0 for messages.
  static size_t PrimitiveBytes(Kind kind);
  static size_t SaturatingMul(size_t a, size_t b);  // a·b, or SIZE_MAX when it overflows.
  class Parser;
  class Walker;

  MessageDefinition() = default;
  Status ResolveOne(const std::string& path, std::vector<uint32_t>* fields,
                    const Field** leaf) const;
  Status NoField(const std::string& path) const;
  void AppendNumericFields(int32_t type, const std::string& prefix,
                           std::vector<std::string>* out) const;

  WireFormat format_ = WireFormat::kRos1;
  uint64_t id_ = 0;
  std::vector<Type> types_;  // types_[0] is the message's own type.
};

}  // namespace calib

#endif  // CALIB_CORE_BAG_MESSAGE_DEFINITION_H_
