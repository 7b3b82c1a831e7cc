#include <calib/core/bag/message_definition.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

// The paths of a parsed definition: resolving, listing, typing them (parsing:
// message_definition_parse.cc; reading messages: message_definition_read.cc).
namespace calib {

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

size_t MessageDefinition::SaturatingMul(size_t a, size_t b) {
  return b != 0 && a > SIZE_MAX / b ? SIZE_MAX : a * b;
}

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

}  // namespace calib
