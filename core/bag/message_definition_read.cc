#include <calib/core/bag/byte_order.h>
#include <calib/core/bag/message_definition.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

// Reading a message's numeric fields by walking its bytes through the definition.
namespace calib {

// A cursor over one message that reads the wanted fields and skips the others. Each read checks
// the bytes left; on failure the path of the field is built up as the recursion unwinds.
class MessageDefinition::Walker {
 public:
  Walker(const MessageDefinition& definition, const uint8_t* data, size_t size, size_t start,
         bool swap)
      : types_(definition.types_),
        data_(data),
        size_(size),
        pos_(start),
        origin_(start),
        cdr_(definition.format_ == WireFormat::kCdr),
        swap_(swap) {}

  // Reads the leaves [begin, end), which all lie inside a field of `type` at `depth`; when
  // `finish`, goes on to the type's end (something after it is wanted).
  bool Walk(int32_t type, size_t depth, const Leaf* begin, const Leaf* end, bool finish,
            double* values) {
    const std::vector<Field>& fields = types_[type].fields;
    uint32_t i = 0;
    for (const Leaf* it = begin; it != end;) {
      const uint32_t wanted = it->fields[depth];
      for (; i < wanted; ++i) {
        if (!Skip(fields[i])) return Inside(fields[i]);
      }
      const Field& field = fields[wanted];
      const Leaf* group_end = it;
      while (group_end != end && group_end->fields[depth] == wanted) ++group_end;
      const size_t start = pos_;
      if (it->fields.size() == depth + 1) {
        double value = 0;
        if (!ReadNumber(field, &value)) return Inside(field);
        for (; it != group_end && it->fields.size() == depth + 1; ++it) values[it->output] = value;
      }
      if (it != group_end) {
        // Fields inside this one too (a time and its sec): read it again from its start.
        pos_ = start;
        if (!Walk(field.message, depth + 1, it, group_end, finish || group_end != end, values)) {
          return Inside(field);
        }
        it = group_end;
      }
      i = wanted + 1;
    }
    if (finish) {
      for (; i < fields.size(); ++i) {
        if (!Skip(fields[i])) return Inside(fields[i]);
      }
    }
    return true;
  }

  // Why Walk failed.
  Status status(const std::string& type) const {
    const std::string where = type + ": ";
    switch (error_) {
      case Error::kEnd:
        return Status::InvalidInput(where + "the message's " + std::to_string(size_) +
                                    " bytes end inside field '" + path_ + "'");
      case Error::kCount:
        // Truncated or corrupt, the message cannot hold what it counts.
        return Status::InvalidInput(where + "the message's " + std::to_string(size_) +
                                    " bytes end inside field '" + path_ + "': it counts " +
                                    std::to_string(count_) + " items at byte " +
                                    std::to_string(error_pos_) + ", more than the " +
                                    std::to_string(size_ - error_pos_) + " bytes left can hold");
      case Error::kWString:
        return Status::InvalidInput(where + "field '" + path_ +
                                    "' is a wstring, which is not decoded");
      case Error::kNone:
        break;
    }
    return Status::Internal(where + "the message walk failed without a reason");
  }

 private:
  enum class Error { kNone, kEnd, kCount, kWString };

  // Fails with `field` in front of the path of the failing field inside it.
  bool Inside(const Field& field) {
    path_ = path_.empty() ? field.name : field.name + "." + path_;
    return false;
  }
  bool End() {
    error_ = Error::kEnd;
    return false;
  }

  // CDR pads each primitive to a multiple of its size (at most 8) from the header's end.
  bool Align(size_t bytes) {
    if (!cdr_ || bytes <= 1) return true;
    const size_t pad = (bytes - (pos_ - origin_) % bytes) % bytes;
    if (pad > size_ - pos_) return End();
    pos_ += pad;
    return true;
  }
  bool Advance(size_t bytes) {
    if (bytes > size_ - pos_) return End();
    pos_ += bytes;
    return true;
  }
  template <typename T>
  bool Read(T* value) {
    if (!Align(std::min<size_t>(sizeof(T), 8)) || sizeof(T) > size_ - pos_) return End();
    std::memcpy(value, data_ + pos_, sizeof(T));
    pos_ += sizeof(T);
    if (swap_) *value = ByteSwapped(*value);
    return true;
  }
  template <typename Secs, typename Nsecs>
  bool ReadTime(double* value) {
    Secs secs = 0;
    Nsecs nsecs = 0;
    if (!Read(&secs) || !Read(&nsecs)) return false;
    *value = static_cast<double>(secs) + 1e-9 * static_cast<double>(nsecs);
    return true;
  }
  template <typename T>
  bool ReadAs(double* value) {
    T raw{};
    if (!Read(&raw)) return false;
    *value = static_cast<double>(raw);
    return true;
  }

  // A numeric field, resolved as such (not an array).
  bool ReadNumber(const Field& field, double* value) {
    const Kind kind = field.kind == Kind::kMessage ? types_[field.message].time : field.kind;
    switch (kind) {
      case Kind::kBool: {
        uint8_t raw = 0;
        if (!Read(&raw)) return false;
        *value = raw != 0 ? 1.0 : 0.0;
        return true;
      }
      case Kind::kInt8:
        return ReadAs<int8_t>(value);
      case Kind::kUint8:
        return ReadAs<uint8_t>(value);
      case Kind::kInt16:
        return ReadAs<int16_t>(value);
      case Kind::kUint16:
        return ReadAs<uint16_t>(value);
      case Kind::kInt32:
        return ReadAs<int32_t>(value);
      case Kind::kUint32:
        return ReadAs<uint32_t>(value);
      case Kind::kInt64:
        return ReadAs<int64_t>(value);
      case Kind::kUint64:
        return ReadAs<uint64_t>(value);
      case Kind::kFloat32:
        return ReadAs<float>(value);
      case Kind::kFloat64:
        return ReadAs<double>(value);
      case Kind::kTime:
        // ROS 1 time is unsigned; ROS 2's Time (int32 sec, uint32 nanosec) is a message.
        return field.kind == Kind::kTime ? ReadTime<uint32_t, uint32_t>(value)
                                         : ReadTime<int32_t, uint32_t>(value);
      case Kind::kDuration:
        return field.kind == Kind::kDuration ? ReadTime<int32_t, int32_t>(value)
                                             : ReadTime<int32_t, uint32_t>(value);
      case Kind::kString:
      case Kind::kWString:
      case Kind::kMessage:
        break;
    }
    return false;  // Unreachable: ResolveOne lets only numbers through.
  }

  bool Skip(const Field& field) {
    switch (field.array) {
      case Array::kNone:
        return SkipElements(field, 1);
      case Array::kFixed:
        return SkipElements(field, field.length);
      case Array::kSequence: {
        uint32_t count = 0;
        if (!Read(&count)) return false;
        const size_t least = field.kind == Kind::kMessage ? types_[field.message].min_bytes
                             : field.kind == Kind::kTime || field.kind == Kind::kDuration ? 8
                             : field.kind == Kind::kString || field.kind == Kind::kWString
                                 ? 4
                                 : PrimitiveBytes(field.kind);
        if (least > 0 && count > (size_ - pos_) / least) {
          error_ = Error::kCount;
          count_ = count;
          error_pos_ = pos_;
          return false;
        }
        return SkipElements(field, count);
      }
    }
    return false;
  }

  // `count` elements of the field's type.
  bool SkipElements(const Field& field, size_t count) {
    if (count == 0) return true;
    switch (field.kind) {
      case Kind::kTime:
      case Kind::kDuration:
        return Align(4) && Advance(SaturatingMul(count, 8));
      case Kind::kString:
        for (size_t i = 0; i < count; ++i) {
          uint32_t length = 0;
          if (!Read(&length) || !Advance(length)) return false;
        }
        return true;
      case Kind::kWString:
        error_ = Error::kWString;
        return false;
      case Kind::kMessage: {
        const Type& type = types_[field.message];
        if (type.min_bytes == 0) return true;  // Nothing on the wire (ROS 1 empty messages).
        if (type.fixed_bytes != kVariable) return Advance(SaturatingMul(count, type.fixed_bytes));
        // Each element takes min_bytes > 0 or fails: the loop ends with the message.
        for (size_t i = 0; i < count; ++i) {
          if (!SkipType(type)) return false;
        }
        return true;
      }
      default: {
        const size_t bytes = PrimitiveBytes(field.kind);
        return Align(bytes) && Advance(SaturatingMul(count, bytes));
      }
    }
  }

  bool SkipType(const Type& type) {
    if (type.fields.empty()) return Advance(type.min_bytes);  // CDR's dummy uint8.
    for (const Field& field : type.fields) {
      if (!Skip(field)) return Inside(field);
    }
    return true;
  }

  const std::vector<Type>& types_;
  const uint8_t* const data_;
  const size_t size_;
  size_t pos_;
  const size_t origin_;
  const bool cdr_;
  const bool swap_;
  Error error_ = Error::kNone;
  std::string path_;
  uint64_t count_ = 0;
  size_t error_pos_ = 0;
};

Status MessageDefinition::ReadNumbers(const uint8_t* data, size_t size, const ResolvedPaths& paths,
                                      std::vector<double>* values) const {
  if (paths.definition_id_ != id_) {
    return Status::Internal("paths resolved for another message definition than " + type() + "'s");
  }
  values->assign(paths.size(), 0.0);
  bool swap = !kHostLittleEndian;
  size_t start = 0;
  if (format_ == WireFormat::kCdr) {
    if (size < kCdrHeaderBytes) {
      return Status::InvalidInput(type() + ": the message's " + std::to_string(size) +
                                  " bytes end inside the CDR encapsulation header");
    }
    if (data[0] != 0 || data[1] > 1) {
      static const char kHex[] = "0123456789abcdef";
      const std::string kind = {kHex[data[0] >> 4], kHex[data[0] & 15], ' ', kHex[data[1] >> 4],
                                kHex[data[1] & 15]};
      return Status::InvalidInput(type() + ": unsupported CDR encapsulation " + kind +
                                  " (plain CDR, XCDR1, 00 00 or 00 01, is read)");
    }
    swap = (data[1] == 1) != kHostLittleEndian;
    start = kCdrHeaderBytes;
  }
  if (paths.leaves_.empty()) return Status::Ok();
  Walker walker(*this, data, size, start, swap);
  if (!walker.Walk(0, 0, paths.leaves_.data(), paths.leaves_.data() + paths.leaves_.size(), false,
                   values->data())) {
    return walker.status(type());
  }
  return Status::Ok();
}

StatusOr<std::vector<double>> MessageDefinition::ReadNumbers(
    const uint8_t* data, size_t size, const std::vector<std::string>& paths) const {
  CALIB_ASSIGN_OR_RETURN(const ResolvedPaths resolved, Resolve(paths));
  std::vector<double> values;
  CALIB_RETURN_IF_ERROR(ReadNumbers(data, size, resolved, &values));
  return values;
}

}  // namespace calib
