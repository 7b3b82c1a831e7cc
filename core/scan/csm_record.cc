#include <calib/core/scan/csm_record.h>
#include <calib/core/text_number.h>

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

namespace calib {
namespace {

using nlohmann::json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

CsmValue* Field(std::string_view key, CsmRecord* r) {
  struct Entry {
    std::string_view key;
    CsmValue CsmRecord::*value;
  };
  static constexpr Entry kFields[] = {
      {"readings", &CsmRecord::readings},
      {"valid", &CsmRecord::valid},
      {"theta", &CsmRecord::theta},
      {"min_theta", &CsmRecord::min_theta},
      {"max_theta", &CsmRecord::max_theta},
      {"nrays", &CsmRecord::nrays},
      {"timestamp", &CsmRecord::timestamp},
      {"left", &CsmRecord::left},
      {"right", &CsmRecord::right},
      {"leftTimestamp", &CsmRecord::left_timestamp},
      {"rightTimestamp", &CsmRecord::right_timestamp},
      {"odometry", &CsmRecord::odometry},
  };
  for (const Entry& e : kFields) {
    if (e.key == key) return &(r->*e.value);
  }
  return nullptr;
}

void Clear(CsmRecord* r) {
  for (CsmValue* v :
       {&r->readings, &r->valid, &r->theta, &r->min_theta, &r->max_theta, &r->nrays, &r->timestamp,
        &r->left, &r->right, &r->left_timestamp, &r->right_timestamp, &r->odometry}) {
    v->kind = CsmValue::Kind::kAbsent;
    v->array.clear();
  }
}

// The direct path: a cursor over one record that gives up (false) on anything it does not know,
// leaving that record to the JSON parser.
class FastRecord {
 public:
  explicit FastRecord(std::string_view s) : p_(s.data()), end_(s.data() + s.size()) {}

  bool Parse(CsmRecord* r) {
    if (!Eat('{')) return false;
    if (Eat('}')) return AtEnd();
    while (true) {
      std::string_view key;
      if (!String(&key) || !Eat(':')) return false;
      CsmValue* value = Field(key, r);
      if (!(value != nullptr ? Value(value) : Skip())) return false;
      if (Eat(',')) continue;
      return Eat('}') && AtEnd();
    }
  }

 private:
  void Space() {
    while (p_ < end_ && (*p_ == ' ' || *p_ == '\n' || *p_ == '\r' || *p_ == '\t')) ++p_;
  }
  bool Eat(char c) {
    Space();
    if (p_ == end_ || *p_ != c) return false;
    ++p_;
    return true;
  }
  bool AtEnd() {
    Space();
    return p_ == end_;
  }
  bool Word(std::string_view w) {
    if (static_cast<size_t>(end_ - p_) < w.size() || std::string_view(p_, w.size()) != w) {
      return false;
    }
    p_ += w.size();
    return true;
  }
  // A string without escapes.
  bool String(std::string_view* s) {
    if (!Eat('"')) return false;
    const char* begin = p_;
    while (p_ < end_ && *p_ != '"') {
      if (*p_ == '\\') return false;
      ++p_;
    }
    if (p_ == end_) return false;
    *s = std::string_view(begin, p_ - begin);
    ++p_;
    return true;
  }
  // A number, null, true or false as a double: NaN where it is no (finite) number.
  bool Scalar(double* v) {
    Space();
    if (Word("null") || Word("true") || Word("false")) {
      *v = kNaN;
      return true;
    }
    NumberStatus status;
    const char* stop = ScanDouble(p_, end_, v, &status);
    if (status == NumberStatus::kNotFinite) *v = kNaN;  // NaN, Infinity as Python writes them.
    if (stop == p_ || (status != NumberStatus::kOk && status != NumberStatus::kNotFinite)) {
      return false;
    }
    p_ = stop;
    return true;
  }
  bool Value(CsmValue* v) {
    Space();
    if (p_ < end_ && *p_ == '[') {
      ++p_;
      v->kind = CsmValue::Kind::kArray;
      v->array.clear();
      if (Eat(']')) return true;
      do {
        double x;
        if (!Scalar(&x)) return false;
        v->array.push_back(x);
      } while (Eat(','));
      return Eat(']');
    }
    if (p_ < end_ && (*p_ == '"' || *p_ == '{')) {
      v->kind = CsmValue::Kind::kOther;
      return Skip();
    }
    double x;
    if (!Scalar(&x)) return false;
    v->kind = std::isnan(x) ? CsmValue::Kind::kOther : CsmValue::Kind::kNumber;
    v->number = x;
    return true;
  }
  // Any value of a field the reader does not use: a scalar, a string, or nested brackets
  // balanced (their strings without escapes).
  bool Skip() {
    Space();
    if (p_ == end_) return false;
    std::string_view s;
    if (*p_ == '"') return String(&s);
    if (*p_ != '[' && *p_ != '{') {
      double x;
      return Scalar(&x);
    }
    int depth = 0;
    while (p_ < end_) {
      const char c = *p_;
      if (c == '"') {
        if (!String(&s)) return false;
        continue;
      }
      ++p_;
      if (c == '[' || c == '{') ++depth;
      if ((c == ']' || c == '}') && --depth == 0) return true;
    }
    return false;
  }

  const char* p_;
  const char* end_;
};

// Python's json writes NaN and Infinity, which JSON has not: read as null.
std::string NullForNonFinite(std::string_view text) {
  std::string out;
  bool in_string = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      out += c;
      if (c == '\\' && i + 1 < text.size()) out += text[++i];
      if (c == '"') in_string = false;
      continue;
    }
    if (c == '"') in_string = true;
    bool replaced = false;
    for (std::string_view word : {"-Infinity", "Infinity", "NaN", "-inf", "inf", "nan"}) {
      if (text.substr(i, word.size()) == word) {
        out += "null";
        i += word.size() - 1;
        replaced = true;
        break;
      }
    }
    if (!replaced) out += c;
  }
  return out;
}

void FromJson(const json& j, CsmValue* v) {
  if (j.is_number()) {
    v->number = j.get<double>();
    v->kind = std::isfinite(v->number) ? CsmValue::Kind::kNumber : CsmValue::Kind::kOther;
  } else if (j.is_array()) {
    v->kind = CsmValue::Kind::kArray;
    v->array.clear();
    for (const json& e : j) v->array.push_back(e.is_number() ? e.get<double>() : kNaN);
  } else {
    v->kind = CsmValue::Kind::kOther;
  }
}

}  // namespace

bool ParseCsmRecord(std::string_view bytes, CsmRecord* record) {
  Clear(record);
  if (FastRecord(bytes).Parse(record)) return true;
  Clear(record);
  json j = json::parse(bytes.begin(), bytes.end(), nullptr, false);
  if (j.is_discarded()) j = json::parse(NullForNonFinite(bytes), nullptr, false);
  if (j.is_discarded() || !j.is_object()) return false;
  for (const auto& [key, value] : j.items()) {
    if (CsmValue* v = Field(key, record)) FromJson(value, v);
  }
  return true;
}

}  // namespace calib
