#ifndef CALIB_CORE_STATUS_H_
#define CALIB_CORE_STATUS_H_

#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <utility>

namespace calib {

// What kind of failure a Status reports; code branches on this, never on the message.
enum class StatusCode {
  kOk,
  kInvalidInput,   // The input is malformed or breaks an invariant (names file, line, record).
  kNotObservable,  // Well-formed data that cannot determine what was asked (e.g. no turning).
  kNotConverged,   // An iterative solver stopped before convergence.
  kIo,             // A file could not be opened, read or written.
  kInternal,       // A bug: an invariant of the library itself was broken.
};

// "invalid input", "not observable", ...
const char* StatusCodeName(StatusCode code);

// The library never throws, prints or exits: failures come back as a Status whose message names
// what is wrong and where (file, line, record), ready to show to a person.
class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}
  static Status Ok() { return Status(); }
  static Status InvalidInput(std::string m) { return {StatusCode::kInvalidInput, std::move(m)}; }
  static Status NotObservable(std::string m) { return {StatusCode::kNotObservable, std::move(m)}; }
  static Status NotConverged(std::string m) { return {StatusCode::kNotConverged, std::move(m)}; }
  static Status Io(std::string m) { return {StatusCode::kIo, std::move(m)}; }
  static Status Internal(std::string m) { return {StatusCode::kInternal, std::move(m)}; }

  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  // The same failure with `context` in front of its message ("file.csv: " + message).
  Status Prefixed(const std::string& context) const {
    return ok() ? *this : Status(code_, context + message_);
  }

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

inline const char* StatusCodeName(StatusCode code) {
  switch (code) {
    case StatusCode::kOk:
      return "ok";
    case StatusCode::kInvalidInput:
      return "invalid input";
    case StatusCode::kNotObservable:
      return "not observable";
    case StatusCode::kNotConverged:
      return "not converged";
    case StatusCode::kIo:
      return "i/o error";
    case StatusCode::kInternal:
      return "internal error";
  }
  return "unknown";
}

// A value or the Status explaining why there is none. Reading the value of a failed StatusOr is
// a programming error: it stops the program with the status' message instead of reading garbage.
template <typename T>
class [[nodiscard]] StatusOr {
 public:
  StatusOr(T value) : value_(std::move(value)) {}  // NOLINT: implicit by design.
  StatusOr(Status status)                          // NOLINT
      : status_(status.ok() ? Status::Internal("StatusOr made from an OK status")
                            : std::move(status)) {}

  bool ok() const { return value_.has_value(); }
  const Status& status() const { return status_; }
  StatusCode code() const { return status_.code(); }
  const std::string& message() const { return status_.message(); }
  const T& value() const& { return Checked(), *value_; }
  T& value() & { return Checked(), *value_; }
  T&& value() && { return Checked(), std::move(*value_); }
  const T& operator*() const& { return value(); }
  T& operator*() & { return value(); }
  T&& operator*() && { return std::move(*this).value(); }
  const T* operator->() const { return &value(); }
  T* operator->() { return &value(); }

 private:
  void Checked() const {
    if (!value_.has_value()) {
      std::fprintf(stderr, "calib: value of a failed StatusOr read (%s): %s\n",
                   StatusCodeName(status_.code()), status_.message().c_str());
      std::abort();
    }
  }
  std::optional<T> value_;
  Status status_;
};

namespace status_internal {
inline const Status& AsStatus(const Status& s) { return s; }
template <typename T>
const Status& AsStatus(const StatusOr<T>& s) {
  return s.status();
}
}  // namespace status_internal

}  // namespace calib

// Returns the Status of `expr` (a Status or StatusOr) from the calling function when it failed.
#define CALIB_RETURN_IF_ERROR(expr)                                      \
  do {                                                                   \
    const auto& calib_status_or_value_ = (expr);                         \
    if (!calib_status_or_value_.ok()) {                                  \
      return ::calib::status_internal::AsStatus(calib_status_or_value_); \
    }                                                                    \
  } while (false)

#define CALIB_STATUS_CONCAT_INNER_(a, b) a##b
#define CALIB_STATUS_CONCAT_(a, b) CALIB_STATUS_CONCAT_INNER_(a, b)

// `CALIB_ASSIGN_OR_RETURN(T x, F());` declares (or assigns) x from a StatusOr, or returns its
// Status from the calling function.
#define CALIB_ASSIGN_OR_RETURN(lhs, expr) \
  CALIB_ASSIGN_OR_RETURN_IMPL_(CALIB_STATUS_CONCAT_(calib_status_or_, __LINE__), lhs, expr)
#define CALIB_ASSIGN_OR_RETURN_IMPL_(tmp, lhs, expr) \
  auto tmp = (expr);                                 \
  if (!tmp.ok()) return tmp.status();                \
  lhs = std::move(tmp).value()

#endif  // CALIB_CORE_STATUS_H_
