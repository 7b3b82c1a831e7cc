#include <calib/core/laser/laser_log_builder.h>
#include <calib/core/laser/laser_log_io.h>
#include <calib/core/text_file.h>
#include <calib/core/text_number.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <exception>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

namespace calib {
namespace {

using laser_io_internal::CheckWritable;
using laser_io_internal::IsJsonSpace;
using laser_io_internal::LogBuilder;
using laser_io_internal::Where;

// ---------------------------------------------------------------------------------------------
// JSON tuples: a hand-written scanner for exactly the subset the published files use.

// The shortest record, {"T":1,"phi_l":1,"phi_r":1,"sm":[1,1,1]}, less a margin.
constexpr size_t kMinRecordBytes = 32;

enum TupleKey { kKeyT, kKeyPhiL, kKeyPhiR, kKeySm, kKeyStart, kNumKeys };
constexpr const char* kTupleKeyNames[kNumKeys] = {"T", "phi_l", "phi_r", "sm", "t"};

// Records parsed without the checks across records (LogBuilder::Add), with whether each had t:
// a part of a long text parsed on its own thread, its lines and records counted from the part's
// start.
struct RawRecords {
  // On mappings of their own: temporaries in the heap left holes that later, larger blocks could
  // not use (a million intervals peaked 18–40 MB higher).
  std::vector<LaserInterval, MappedAllocator<LaserInterval>> intervals;
  std::vector<char, MappedAllocator<char>> has_t;
};

class TupleParser {
 public:
  // `release_bytes`: how much text may stay resident between calls of `release`.
  TupleParser(std::string_view text, const std::string& source, const ReleaseText& release,
              size_t release_bytes = kReleaseTextBytes)
      : p_(text.data()),
        end_(text.data() + text.size()),
        builder_(source),
        source_(source),
        release_(release),
        release_bytes_(release_bytes) {
    released_ = p_;
    next_release_ = Ahead(p_);
  }

  // Room for the records of `text` (an estimate from its braces, bounded by its bytes).
  void Reserve(std::string_view text) { builder_.Reserve(EstimateRecords(text)); }
  static size_t EstimateRecords(std::string_view text) {
    return std::min(EstimateByteCount(text, '{'), text.size() / kMinRecordBytes);
  }

  StatusOr<LaserLog> Parse() {
    CALIB_RETURN_IF_ERROR(ParseRecords(nullptr));
    return Finish();
  }

  // Every record of the text into the log, or into *raw when given.
  Status ParseRecords(RawRecords* raw) {
    SkipSpace();
    while (p_ < end_) {
      if (*p_ != '{') {
        const std::string after =
            record_ > 0 ? "after record " + std::to_string(record_) + ": " : "";
        return Status::InvalidInput(Where(source_, line_, 0) + after + "unexpected text '" +
                                    Token() +
                                    "' between records (each record is a { ... } object)");
      }
      LaserInterval interval;
      bool has_t = false;
      CALIB_RETURN_IF_ERROR(ParseBoundedRecord(&interval, &has_t));
      if (raw != nullptr) {
        raw->intervals.push_back(std::move(interval));
        raw->has_t.push_back(has_t);
      } else {
        CALIB_RETURN_IF_ERROR(builder_.Add(std::move(interval), has_t));
      }
      SkipSpace();
      if (release_ && p_ >= next_release_) {
        release_(released_, p_);
        released_ = p_;
        next_release_ = Ahead(p_);
      }
    }
    return Status::Ok();
  }

  // Adds the records of the text that follows this parser's (parsed by ParseRecords into `raw`),
  // numbering their lines and records on from this parser's.
  Status AddFollowing(RawRecords raw) {
    const int64_t lines_before = line_ - 1;
    for (size_t k = 0; k < raw.intervals.size(); ++k) {
      LaserInterval& interval = raw.intervals[k];
      interval.line = SaturatedInt(interval.line + lines_before);
      interval.record = SaturatedInt(interval.record + record_);
      CALIB_RETURN_IF_ERROR(builder_.Add(std::move(interval), raw.has_t[k]));
    }
    return Status::Ok();
  }

  StatusOr<LaserLog> Finish() { return std::move(builder_).Finish(""); }

 private:
  void SkipSpace() {
    while (p_ < end_) {
      const char c = *p_;
      if (c == '\n') {
        ++line_;
      } else if (c != ' ' && c != '\t' && c != '\r') {
        break;
      }
      ++p_;
    }
  }

  // A short excerpt of the input at p_ for messages.
  std::string Token() const {
    if (p_ >= end_) return "end of input";
    const char* q = p_;
    while (q < end_ && q - p_ < 24 && !IsJsonSpace(*q) && *q != ',' && *q != '}' && *q != ']' &&
           *q != '{' && *q != ':') {
      ++q;
    }
    if (q == p_) ++q;
    return std::string(p_, q);
  }

  Status Error(const std::string& problem) const {
    return Status::InvalidInput(Where(source_, line_, record_) + problem);
  }
  // Names the line where the record started, which is where a reader looks.
  Status Truncated(const char* inside) const {
    return Status::InvalidInput(Where(source_, record_line_, record_) +
                                "truncated record: the input ends inside " + inside);
  }

  Status ParseNumber(const char* key, double* value) {
    if (p_ >= end_) return Truncated("the record");
    NumberStatus status;
    const char* stop = ScanDouble(p_, end_, value, &status);
    if (status == NumberStatus::kNotNumber ||
        (stop < end_ && !IsJsonSpace(*stop) && *stop != ',' && *stop != '}' && *stop != ']')) {
      return Error(NumberProblem(NumberStatus::kNotNumber, key, Token()));
    }
    if (status != NumberStatus::kOk) return Error(NumberProblem(status, key, Token()));
    p_ = stop;
    return Status::Ok();
  }

  Status ParseSm(Pose2d* sm) {
    if (p_ >= end_) return Truncated("the record");
    if (*p_ != '[') return Error("sm must be an array of 3 numbers, got '" + Token() + "'");
    ++p_;
    SkipSpace();
    if (p_ >= end_) return Truncated("the sm array");
    int count = 0;
    if (*p_ == ']') {
      ++p_;
    } else {
      while (true) {
        double value = 0.0;
        CALIB_RETURN_IF_ERROR(ParseNumber("sm", &value));
        if (count < 3) (*sm)(count) = value;
        ++count;
        SkipSpace();
        if (p_ >= end_) return Truncated("the sm array");
        if (*p_ == ']') {
          ++p_;
          break;
        }
        if (*p_ != ',') return Error("expected ',' or ']' in sm, got '" + Token() + "'");
        ++p_;
        SkipSpace();
        if (p_ >= end_) return Truncated("the sm array");
      }
    }
    if (count != 3) {
      return Error("sm must hold 3 numbers (x, y, theta), got " + std::to_string(count));
    }
    return Status::Ok();
  }

  // A record is parsed with the input cut kMaxLineBytes after its '{', so that no record costs
  // more than that (several records may share a line: the bound is per record).
  Status ParseBoundedRecord(LaserInterval* interval, bool* has_t) {
    const char* const end = end_;
    const bool cut = static_cast<size_t>(end - p_) > kMaxLineBytes;
    if (cut) end_ = p_ + kMaxLineBytes;
    Status status = ParseRecord(interval, has_t);
    if (!status.ok() && cut && p_ >= end_) {
      status = Status::InvalidInput(Where(source_, record_line_, record_) + "record longer than " +
                                    std::to_string(kMaxLineBytes) +
                                    " bytes without its closing '}' (the limit of one record)");
    }
    end_ = end;
    return status;
  }

  Status ParseRecord(LaserInterval* interval, bool* has_t) {
    ++record_;
    record_line_ = line_;
    interval->line = SaturatedInt(line_);
    interval->record = SaturatedInt(record_);
    ++p_;  // '{'
    bool seen[kNumKeys] = {};
    double values[kNumKeys] = {};
    SkipSpace();
    if (p_ < end_ && *p_ == '}') {
      ++p_;
    } else {
      while (true) {
        SkipSpace();
        if (p_ >= end_) return Truncated("the record");
        if (*p_ != '"') return Error("expected a quoted key, got '" + Token() + "'");
        const char* key_begin = ++p_;
        while (p_ < end_ && *p_ != '"' && *p_ != '\n') ++p_;
        if (p_ >= end_) return Truncated("a key");
        if (*p_ != '"') return Error("unterminated key");
        const std::string_view key(key_begin, static_cast<size_t>(p_ - key_begin));
        ++p_;
        int index = 0;
        while (index < kNumKeys && key != kTupleKeyNames[index]) ++index;
        if (index == kNumKeys) {
          return Error("unknown key \"" + std::string(key) +
                       "\" (expected T, phi_l, phi_r, sm and optionally t)");
        }
        if (seen[index]) return Error("duplicate key \"" + std::string(key) + "\"");
        seen[index] = true;
        SkipSpace();
        if (p_ >= end_) return Truncated("the record");
        if (*p_ != ':') return Error("expected ':' after \"" + std::string(key) + "\"");
        ++p_;
        SkipSpace();
        if (index == kKeySm) {
          CALIB_RETURN_IF_ERROR(ParseSm(&interval->sensor_motion));
        } else {
          if (p_ < end_ && *p_ == '[') {
            return Error(std::string(kTupleKeyNames[index]) + " must be a number, not an array");
          }
          CALIB_RETURN_IF_ERROR(ParseNumber(kTupleKeyNames[index], &values[index]));
        }
        SkipSpace();
        if (p_ >= end_) return Truncated("the record");
        if (*p_ == '}') {
          ++p_;
          break;
        }
        if (*p_ != ',') {
          return Error("expected ',' or '}' after the value of \"" + std::string(key) +
                       "\", got '" + Token() + "'");
        }
        ++p_;
      }
    }
    for (int index = 0; index < kKeyStart; ++index) {
      if (!seen[index]) {
        return Status::InvalidInput(Where(source_, record_line_, record_) + "missing key \"" +
                                    kTupleKeyNames[index] + "\"");
      }
    }
    interval->duration_s = values[kKeyT];
    interval->left_speed = values[kKeyPhiL];
    interval->right_speed = values[kKeyPhiR];
    interval->start_s = values[kKeyStart];
    *has_t = seen[kKeyStart];
    return Status::Ok();
  }

  const char* p_;
  const char* end_;
  LogBuilder builder_;
  const std::string& source_;
  const ReleaseText& release_;
  size_t release_bytes_;
  const char* released_ = nullptr;  // The text before it was released.
  const char* next_release_ = nullptr;

  // release_bytes_ past q, or the end.
  const char* Ahead(const char* q) const {
    return static_cast<size_t>(end_ - q) > release_bytes_ ? q + release_bytes_ : end_;
  }
  // 64 bits: a file may hold more than 2^31 newlines.
  int64_t line_ = 1;
  int64_t record_ = 0;
  int64_t record_line_ = 0;
};

// Below this size a text is parsed in one pass (a thread costs more than half its parse).
constexpr size_t kParseInHalvesBytes = size_t{4} << 20;

// Where a record starts on a line of its own near `at`: the start of the line after the first
// newline from `at` whose next character after spaces is '{' (npos: none within a record's
// bound). A record holds no '{' of its own, so when the text before parses whole, one starts here.
size_t RecordBoundaryNear(std::string_view text, size_t at) {
  const size_t stop = std::min(text.size(), at + kMaxLineBytes);
  for (size_t i = text.find('\n', at); i < stop; i = text.find('\n', i + 1)) {
    size_t j = i + 1;
    while (j < text.size() && (text[j] == ' ' || text[j] == '\t' || text[j] == '\r')) ++j;
    if (j < text.size() && text[j] == '{') return i + 1;
  }
  return std::string_view::npos;
}

// A long text parsed in two halves at once, the second on its own thread, its records then added
// after the first's: the same log as one pass, in about half the time. Nothing when the text is
// short, has no record boundary near its middle, a thread cannot start, or either half fails: the
// caller then parses in one pass, which reports the first error with its line.
std::optional<StatusOr<LaserLog>> ParseInHalves(std::string_view text, const std::string& source,
                                                const ReleaseText& release) {
  if (text.size() < kParseInHalvesBytes) return std::nullopt;
  const size_t split = RecordBoundaryNear(text, text.size() / 2);
  if (split == std::string_view::npos) return std::nullopt;
  TupleParser first(text.substr(0, split), source, release, kReleaseTextBytes / 2);
  TupleParser second(text.substr(split), source, release, kReleaseTextBytes / 2);
  RawRecords raw;
  const size_t second_records = TupleParser::EstimateRecords(text.substr(split));
  Status second_status = Status::Internal("not parsed");
  // The thread starts before the log's records are reserved and puts nothing in the heap: with
  // the thread's start or its arrays in the heap above the records, a million intervals peaked
  // 18 MB higher (measured; memory freed below them no longer rejoined the heap's top).
  std::thread thread;
  try {
    thread = std::thread([&] {
      try {
        raw.intervals.reserve(second_records);
        raw.has_t.reserve(second_records);
        second_status = second.ParseRecords(&raw);
      } catch (const std::exception&) {  // Out of memory: the one pass then reports it.
        second_status = Status::Internal("out of memory");
      }
    });
  } catch (const std::system_error&) {
    return std::nullopt;
  }
  Status first_status;
  try {
    first.Reserve(text);
    first_status = first.ParseRecords(nullptr);
  } catch (...) {
    thread.join();
    throw;
  }
  thread.join();
  if (!first_status.ok() || !second_status.ok()) return std::nullopt;
  const Status added = first.AddFollowing(std::move(raw));
  if (!added.ok()) return StatusOr<LaserLog>(added);
  return first.Finish();
}

}  // namespace

StatusOr<LaserLog> ParseLaserTuples(std::string_view text, const std::string& source,
                                    const ReleaseText& release) {
  return GuardAllocation(source, [&]() -> StatusOr<LaserLog> {
    const std::string_view body = WithoutBom(text);
    std::optional<StatusOr<LaserLog>> halves = ParseInHalves(body, source, release);
    if (halves) return std::move(*halves);
    TupleParser parser(body, source, release);
    parser.Reserve(body);
    return parser.Parse();
  });
}

Status WriteLaserTuples(const LaserLog& log, const std::string& path) {
  CALIB_RETURN_IF_ERROR(CheckWritable(log, path));
  std::string out;
  out.reserve(log.intervals.size() * 160);
  for (const LaserInterval& interval : log.intervals) {
    out += "{ ";
    if (log.has_timestamps) {
      out += "\"t\": ";
      AppendScientific(&out, interval.start_s);
      out += ", ";
    }
    out += "\"T\": ";
    AppendScientific(&out, interval.duration_s);
    out += ", \"phi_l\": ";
    AppendScientific(&out, interval.left_speed);
    out += ", \"phi_r\": ";
    AppendScientific(&out, interval.right_speed);
    out += ", \"sm\": [ ";
    AppendScientific(&out, interval.sensor_motion(0));
    out += ", ";
    AppendScientific(&out, interval.sensor_motion(1));
    out += ", ";
    AppendScientific(&out, interval.sensor_motion(2));
    out += " ] }\n";
  }
  return WriteWholeFile(path, out);
}

}  // namespace calib
