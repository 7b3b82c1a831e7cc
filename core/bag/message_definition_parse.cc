#include <calib/core/bag/message_definition.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdint>
#include <map>
#include <utility>

// Parsing a message definition's text into its types.
namespace calib {
namespace {

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

}  // namespace

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

}  // namespace calib
