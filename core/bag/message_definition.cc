#include <calib/core/bag/message_definition.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <map>
#include <utility>

namespace calib {
namespace {

constexpr bool kHostLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;
constexpr size_t kCdrHeaderBytes = 4;
// Deeper nesting than real messages ever have; bounds the recursion of parsing and walking.
constexpr int kMaxDepth = 64;

// Tells ResolvedPaths of different definitions apart (copies of one definition share its id).
std::atomic<uint64_t> next_definition_id{1};

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string Trimmed(const std::string& s) {
  size_t begin = 0, end = s.size();
  while (begin < end && IsSpace(s[begin])) ++begin;
  while (end > begin && IsSpace(s[end - 1])) --end;
  return s.substr(begin, end - begin);
}

bool IsIdentifier(const std::string& s) {
  if (s.empty() || !std::isalpha(static_cast<unsigned char>(s[0]))) return false;
  for (char c : s) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  }
  return true;
}

// A decimal count of at most uint32 range, or false.
bool ParseCount(const std::string& s, uint32_t* out) {
  if (s.empty() || s.size() > 10) return false;
  uint64_t value = 0;
  for (char c : s) {
    if (c < '0' || c > '9') return false;
    value = value * 10 + static_cast<uint64_t>(c - '0');
  }
  if (value > UINT32_MAX) return false;
  *out = static_cast<uint32_t>(value);
  return true;
}

// "pkg/Type" from "pkg/Type" or "pkg/msg/Type", or "" when `name` is neither.
std::string NormalizedTypeName(const std::string& name) {
  std::vector<std::string> parts;
  size_t begin = 0;
  while (true) {
    const size_t slash = name.find('/', begin);
    parts.push_back(name.substr(begin, slash == std::string::npos ? slash : slash - begin));
    if (slash == std::string::npos) break;
    begin = slash + 1;
  }
  for (const std::string& part : parts) {
    if (!IsIdentifier(part)) return "";
  }
  if (parts.size() == 2) return name;
  if (parts.size() == 3 && parts[1] == "msg") return parts[0] + "/" + parts[2];
  return "";
}

size_t SaturatingAdd(size_t a, size_t b) { return a > SIZE_MAX - b ? SIZE_MAX : a + b; }
size_t SaturatingMul(size_t a, size_t b) { return b != 0 && a > SIZE_MAX / b ? SIZE_MAX : a * b; }

template <typename T>
T ByteSwapped(T value) {
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  std::reverse(bytes, bytes + sizeof(T));
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Parsing.

size_t MessageDefinition::PrimitiveBytes(Kind kind) {
  switch (kind) {
    case Kind::kBool:
    case Kind::kInt8:
    case Kind::kUint8:
      return 1;
    case Kind::kInt16:
    case Kind::kUint16:
      return 2;
    case Kind::kInt32:
    case Kind::kUint32:
    case Kind::kFloat32:
      return 4;
    case Kind::kInt64:
    case Kind::kUint64:
    case Kind::kFloat64:
    case Kind::kTime:
    case Kind::kDuration:
      return 8;
    case Kind::kString:
    case Kind::kWString:
      return 4;  // The least: a length.
    case Kind::kMessage:
      break;
  }
  return 0;
}
class MessageDefinition::Parser {
 public:
  Parser(const std::string& type, WireFormat format) : root_(type), format_(format) {}

  StatusOr<MessageDefinition> Run(const std::string& text) {
    CALIB_RETURN_IF_ERROR(Split(text));
    AddBuiltInTimes();
    MessageDefinition definition;
    definition.format_ = format_;
    definition.id_ = next_definition_id.fetch_add(1);
    types_ = &definition.types_;
    int32_t root = 0;
    CALIB_RETURN_IF_ERROR(Build(0, 0, &root));
    return definition;
  }

 private:
  struct RawField {
    std::string name;
    std::string type;  // Complex type as written, "" for a primitive.
    Kind kind = Kind::kMessage;
    Array array = Array::kNone;
    uint32_t length = 0;
    int line = 0;
  };
  struct Section {
    std::string name;
    std::vector<RawField> fields;
    int type_index = -1;  // In types_, once built.
    bool building = false;
  };

  Status LineError(int line, const std::string& text, const std::string& what) const {
    return Status::InvalidInput("message definition of " + root_ + ", line " +
                                std::to_string(line) + " ('" + text + "'): " + what);
  }

  // The sections of `text`: the root type's fields, then each "MSG: pkg/Type" dependency.
  Status Split(const std::string& text) {
    sections_.push_back({root_, {}});
    bool expect_msg = false;
    int line_number = 0;
    size_t begin = 0;
    while (begin <= text.size()) {
      size_t end = text.find('\n', begin);
      if (end == std::string::npos) end = text.size();
      const std::string line = Trimmed(text.substr(begin, end - begin));
      begin = end + 1;
      ++line_number;
      if (line.size() >= 3 && line.find_first_not_of('=') == std::string::npos) {
        expect_msg = true;
        continue;
      }
      if (line.compare(0, 4, "MSG:") == 0) {
        const std::string name = NormalizedTypeName(Trimmed(line.substr(4)));
        if (name.empty()) return LineError(line_number, line, "expected 'MSG: pkg/Type'");
        sections_.push_back({name, {}});
        expect_msg = false;
        continue;
      }
      if (line.empty() || line[0] == '#') continue;
      if (expect_msg) {
        return LineError(line_number, line, "expected 'MSG: pkg/Type' after the line of '='");
      }
      CALIB_RETURN_IF_ERROR(ParseLine(line_number, line));
    }
    return Status::Ok();
  }

  // A field ("type name", maybe with a ROS 2 default value after it) or a constant
  // ("type NAME=value"), which is skipped.
  Status ParseLine(int line_number, const std::string& line) {
    size_t p = 0;
    while (p < line.size() && !IsSpace(line[p])) ++p;
    const std::string type = line.substr(0, p);
    while (p < line.size() && IsSpace(line[p])) ++p;
    const size_t name_begin = p;
    while (p < line.size() && !IsSpace(line[p]) && line[p] != '=' && line[p] != '#') ++p;
    const std::string name = line.substr(name_begin, p - name_begin);
    while (p < line.size() && IsSpace(line[p])) ++p;
    if (name.empty()) return LineError(line_number, line, "expected 'type name'");
    if (p < line.size() && line[p] == '=') return Status::Ok();  // A constant.
    if (!IsIdentifier(name)) return LineError(line_number, line, "bad field name '" + name + "'");
    RawField field;
    field.name = name;
    field.line = line_number;
    CALIB_RETURN_IF_ERROR(ParseType(line_number, line, type, &field));
    for (const RawField& other : sections_.back().fields) {
      if (other.name == name) return LineError(line_number, line, "a second field '" + name + "'");
    }
    sections_.back().fields.push_back(std::move(field));
    return Status::Ok();
  }

  Status ParseType(int line_number, const std::string& line, std::string type, RawField* field) {
    if (!type.empty() && type.back() == ']') {
      const size_t open = type.rfind('[');
      if (open == std::string::npos) return LineError(line_number, line, "bad array type");
      const std::string inside = type.substr(open + 1, type.size() - open - 2);
      type.resize(open);
      if (inside.empty()) {
        field->array = Array::kSequence;
      } else if (inside.compare(0, 2, "<=") == 0 && ParseCount(inside.substr(2), &field->length)) {
        field->array = Array::kSequence;  // A bounded sequence is serialized like any other.
        field->length = 0;
      } else if (ParseCount(inside, &field->length)) {
        field->array = Array::kFixed;
      } else {
        return LineError(line_number, line, "bad array size '" + inside + "'");
      }
    }
    // Bounded strings are serialized like strings.
    uint32_t bound = 0;
    for (const char* string_type : {"string", "wstring"}) {
      const std::string prefix = std::string(string_type) + "<=";
      if (type.compare(0, prefix.size(), prefix) == 0) {
        if (!ParseCount(type.substr(prefix.size()), &bound)) {
          return LineError(line_number, line, "bad string bound in '" + type + "'");
        }
        type = string_type;
      }
    }
    const bool ros1 = format_ == WireFormat::kRos1;
    static const std::map<std::string, Kind> kPrimitives = {{"bool", Kind::kBool},
                                                            {"int8", Kind::kInt8},
                                                            {"uint8", Kind::kUint8},
                                                            {"int16", Kind::kInt16},
                                                            {"uint16", Kind::kUint16},
                                                            {"int32", Kind::kInt32},
                                                            {"uint32", Kind::kUint32},
                                                            {"int64", Kind::kInt64},
                                                            {"uint64", Kind::kUint64},
                                                            {"float32", Kind::kFloat32},
                                                            {"float64", Kind::kFloat64},
                                                            {"string", Kind::kString},
                                                            {"wstring", Kind::kWString},
                                                            {"time", Kind::kTime},
                                                            {"duration", Kind::kDuration},
                                                            {"char", Kind::kUint8},
                                                            {"byte", Kind::kUint8 /*ROS 2 octet*/}};
    const auto primitive = kPrimitives.find(type);
    if (primitive != kPrimitives.end()) {
      field->kind = type == "byte" && ros1 ? Kind::kInt8 : primitive->second;
      return Status::Ok();
    }
    if (type == "Header") {
      field->type = "std_msgs/Header";
    } else if (type.find('/') == std::string::npos && IsIdentifier(type)) {
      // Same package as the type that names it.
      const std::string& owner = sections_.back().name;
      field->type = owner.substr(0, owner.find('/')) + "/" + type;
    } else {
      field->type = NormalizedTypeName(type);
    }
    if (field->type.empty()) return LineError(line_number, line, "bad type '" + type + "'");
    field->kind = Kind::kMessage;
    return Status::Ok();
  }

  static bool IsTimeStruct(const std::vector<Field>& fields) {
    return fields.size() == 2 && fields[0].name == "sec" && fields[0].kind == Kind::kInt32 &&
           fields[0].array == Array::kNone && fields[1].name == "nanosec" &&
           fields[1].kind == Kind::kUint32 && fields[1].array == Array::kNone;
  }

  // The type of section `index` built into types_ (with the types it uses), its index in `out`.
  Status Build(size_t index, int depth, int32_t* out) {
    Section& section = sections_[index];
    if (section.type_index >= 0) {
      *out = section.type_index;
      return Status::Ok();
    }
    if (section.building) {
      return Status::InvalidInput("message definition of " + root_ + ": " + section.name +
                                  " contains itself");
    }
    if (depth > kMaxDepth) {
      return Status::InvalidInput("message definition of " + root_ + ": types nest deeper than " +
                                  std::to_string(kMaxDepth) + " levels");
    }
    section.building = true;
    const int32_t type_index = static_cast<int32_t>(types_->size());
    types_->push_back({});
    std::vector<Field> fields;
    for (const RawField& raw : sections_[index].fields) {
      Field field;
      field.name = raw.name;
      field.kind = raw.kind;
      field.array = raw.array;
      field.length = raw.length;
      if (raw.kind == Kind::kMessage) {
        const size_t dependency = FindSection(raw.type);
        if (dependency == sections_.size()) {
          return Status::InvalidInput(
              "message definition of " + root_ + ", line " + std::to_string(raw.line) + ": type " +
              raw.type + " of field '" + raw.name + "' (in " + sections_[index].name +
              ") is not defined: the text has no 'MSG: " + raw.type + "' section");
        }
        CALIB_RETURN_IF_ERROR(Build(dependency, depth + 1, &field.message));
      }
      fields.push_back(std::move(field));
    }
    Type& type = (*types_)[type_index];
    type.name = sections_[index].name;
    type.fields = std::move(fields);
    if (IsTimeStruct(type.fields)) {
      if (type.name == "builtin_interfaces/Time") type.time = Kind::kTime;
      if (type.name == "builtin_interfaces/Duration") type.time = Kind::kDuration;
    }
    // ROS 2 gives a type without fields a uint8 member, as CDR has no empty structs.
    const bool cdr = format_ == WireFormat::kCdr;
    type.min_bytes = type.fields.empty() && cdr ? 1 : 0;
    type.fixed_bytes = cdr ? kVariable : 0;
    for (const Field& field : type.fields) {
      const size_t element_min = field.kind == Kind::kMessage ? (*types_)[field.message].min_bytes
                                                              : PrimitiveBytes(field.kind);
      const size_t element_fixed = field.kind == Kind::kMessage
                                       ? (*types_)[field.message].fixed_bytes
                                   : field.kind == Kind::kString || field.kind == Kind::kWString
                                       ? kVariable
                                       : PrimitiveBytes(field.kind);
      switch (field.array) {
        case Array::kNone:
          type.min_bytes = SaturatingAdd(type.min_bytes, element_min);
          break;
        case Array::kFixed:
          type.min_bytes = SaturatingAdd(type.min_bytes, SaturatingMul(element_min, field.length));
          break;
        case Array::kSequence:
          type.min_bytes = SaturatingAdd(type.min_bytes, 4);
          break;
      }
      if (type.fixed_bytes == kVariable) continue;
      if (field.array == Array::kSequence || element_fixed == kVariable) {
        type.fixed_bytes = kVariable;
      } else {
        const size_t bytes = field.array == Array::kFixed
                                 ? SaturatingMul(element_fixed, field.length)
                                 : element_fixed;
        type.fixed_bytes = SaturatingAdd(type.fixed_bytes, bytes);
        if (type.fixed_bytes == SIZE_MAX) type.fixed_bytes = kVariable;
      }
    }
    sections_[index].building = false;
    sections_[index].type_index = type_index;
    *out = type_index;
    return Status::Ok();
  }

  // ROS 2's time types, for texts that leave them out (sections_ must not grow while building).
  void AddBuiltInTimes() {
    for (const char* name : {"builtin_interfaces/Time", "builtin_interfaces/Duration"}) {
      if (FindSection(name) < sections_.size()) continue;
      Section section{name, {}};
      section.fields.push_back({"sec", "", Kind::kInt32, Array::kNone, 0, 0});
      section.fields.push_back({"nanosec", "", Kind::kUint32, Array::kNone, 0, 0});
      sections_.push_back(std::move(section));
    }
  }

  // The section defining `name`, or sections_.size().
  size_t FindSection(const std::string& name) const {
    for (size_t i = 0; i < sections_.size(); ++i) {
      if (sections_[i].name == name) return i;
    }
    return sections_.size();
  }

  const std::string root_;
  const WireFormat format_;
  std::vector<Section> sections_;
  std::vector<Type>* types_ = nullptr;
};

StatusOr<MessageDefinition> MessageDefinition::Parse(const std::string& type,
                                                     const std::string& text, WireFormat format) {
  const std::string name = NormalizedTypeName(type);
  if (name.empty()) {
    return Status::InvalidInput("message type '" + type + "' is not 'pkg/Type' or 'pkg/msg/Type'");
  }
  return Parser(name, format).Run(text);
}

// ---------------------------------------------------------------------------------------------
// Paths.

const std::string& MessageDefinition::type() const { return types_[0].name; }

bool MessageDefinition::has_header() const {
  const std::vector<Field>& fields = types_[0].fields;
  return !fields.empty() && fields[0].name == "header" && fields[0].kind == Kind::kMessage &&
         fields[0].array == Array::kNone && types_[fields[0].message].name == "std_msgs/Header";
}

void MessageDefinition::AppendNumericFields(int32_t type, const std::string& prefix,
                                            std::vector<std::string>* out) const {
  for (const Field& field : types_[type].fields) {
    if (field.array != Array::kNone || field.kind == Kind::kString ||
        field.kind == Kind::kWString) {
      continue;
    }
    if (field.kind == Kind::kMessage && types_[field.message].time == Kind::kMessage) {
      AppendNumericFields(field.message, prefix + field.name + ".", out);
    } else {
      out->push_back(prefix + field.name);
    }
  }
}

std::vector<std::string> MessageDefinition::NumericFields() const {
  std::vector<std::string> out;
  AppendNumericFields(0, "", &out);
  return out;
}

Status MessageDefinition::NoField(const std::string& path) const {
  const std::vector<std::string> numeric = NumericFields();
  std::string list;
  for (const std::string& name : numeric) list += (list.empty() ? "" : ", ") + name;
  return Status::InvalidInput(
      "no field '" + path + "' in " + type() +
      (numeric.empty() ? "; it has no numeric fields" : "; its numeric fields: " + list));
}

namespace {
const char* KindName(int kind) {
  static const char* const kNames[] = {"bool",    "int8",   "uint8",    "int16",  "uint16",
                                       "int32",   "uint32", "int64",    "uint64", "float32",
                                       "float64", "time",   "duration", "string", "wstring"};
  return kind >= 0 && kind < static_cast<int>(sizeof(kNames) / sizeof(kNames[0])) ? kNames[kind]
                                                                                  : "message";
}
}  // namespace

Status MessageDefinition::ResolveOne(const std::string& path, std::vector<uint32_t>* fields,
                                     const Field** leaf) const {
  fields->clear();
  int32_t message = 0;
  const Field* field = nullptr;
  size_t begin = 0;
  while (true) {
    const size_t dot = path.find('.', begin);
    const std::string name =
        path.substr(begin, dot == std::string::npos ? std::string::npos : dot - begin);
    if (field != nullptr) {
      // Only a field that is one message, not an array of them, has fields to name.
      if (field->kind != Kind::kMessage) return NoField(path);
      const std::string walked = path.substr(0, begin - 1);
      if (field->array != Array::kNone) {
        return Status::InvalidInput("field '" + walked + "' of " + type() +
                                    " is an array: fields inside arrays cannot be read");
      }
      message = field->message;
    }
    const std::vector<Field>& candidates = types_[message].fields;
    const auto it = std::find_if(candidates.begin(), candidates.end(),
                                 [&](const Field& f) { return f.name == name; });
    if (it == candidates.end()) return NoField(path);
    fields->push_back(static_cast<uint32_t>(it - candidates.begin()));
    field = &*it;
    if (dot == std::string::npos) break;
    begin = dot + 1;
  }
  const std::string where = "field '" + path + "' of " + type();
  if (field->array != Array::kNone) {
    return Status::InvalidInput(where + " is an array, not a number: fields inside arrays " +
                                "cannot be read");
  }
  if (field->kind == Kind::kString || field->kind == Kind::kWString) {
    return Status::InvalidInput(where + " is a " + KindName(static_cast<int>(field->kind)) +
                                ", not a number");
  }
  if (field->kind == Kind::kMessage && types_[field->message].time == Kind::kMessage) {
    std::vector<std::string> inside;
    AppendNumericFields(field->message, path + ".", &inside);
    std::string list;
    for (const std::string& name : inside) list += (list.empty() ? "" : ", ") + name;
    return Status::InvalidInput(where + " is a " + types_[field->message].name + ", not a number" +
                                (inside.empty() ? "" : "; its numeric fields: " + list));
  }
  *leaf = field;
  return Status::Ok();
}

StatusOr<MessageDefinition::ResolvedPaths> MessageDefinition::Resolve(
    const std::vector<std::string>& paths) const {
  ResolvedPaths resolved;
  resolved.definition_id_ = id_;
  resolved.size_ = paths.size();
  resolved.leaves_.resize(paths.size());
  for (size_t i = 0; i < paths.size(); ++i) {
    const Field* leaf = nullptr;
    CALIB_RETURN_IF_ERROR(ResolveOne(paths[i], &resolved.leaves_[i].fields, &leaf));
    resolved.leaves_[i].output = i;
  }
  // Field indices in definition order are the order of the bytes: one walk reads them all.
  std::sort(resolved.leaves_.begin(), resolved.leaves_.end(),
            [](const Leaf& a, const Leaf& b) { return a.fields < b.fields; });
  return resolved;
}

StatusOr<std::string> MessageDefinition::FieldType(const std::string& path) const {
  std::vector<uint32_t> fields;
  const Field* leaf = nullptr;
  CALIB_RETURN_IF_ERROR(ResolveOne(path, &fields, &leaf));
  const Kind kind = leaf->kind == Kind::kMessage ? types_[leaf->message].time : leaf->kind;
  return std::string(KindName(static_cast<int>(kind)));
}

// ---------------------------------------------------------------------------------------------
// Reading.

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
