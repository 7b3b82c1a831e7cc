#include <calib/core/text_number.h>

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <system_error>

namespace calib {

std::string Num(double value) {
  std::string out;
  AppendGeneral(&out, value);
  return out;
}

void AppendGeneral(std::string* out, double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  out->append(buffer, result.ptr);
}

void AppendScientific(std::string* out, double value) {
  char buffer[32];
  const auto result =
      std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::scientific);
  out->append(buffer, result.ptr);
}

std::string_view WithoutBom(std::string_view text) {
  if (text.size() >= 3 && text.compare(0, 3, "\xEF\xBB\xBF") == 0) text.remove_prefix(3);
  return text;
}

const char* ScanDouble(const char* begin, const char* end, double* value, NumberStatus* status) {
  const auto result = std::from_chars(begin, end, *value);
  if (result.ec == std::errc::invalid_argument) {
    *status = NumberStatus::kNotNumber;
    return begin;
  }
  if (result.ec == std::errc::result_out_of_range) {
    // Underflow to a denormal or zero is harmless; overflow is not. strtod tells them apart.
    const std::string token(begin, result.ptr);
    *value = std::strtod(token.c_str(), nullptr);
    *status = std::isfinite(*value) ? NumberStatus::kOk : NumberStatus::kOutOfRange;
    return result.ptr;
  }
  *status = std::isfinite(*value) ? NumberStatus::kOk : NumberStatus::kNotFinite;
  return result.ptr;
}

NumberStatus ParseDouble(std::string_view field, double* value) {
  if (field.size() > 1 && field.front() == '+') field.remove_prefix(1);  // from_chars rejects it.
  NumberStatus status;
  const char* end = field.data() + field.size();
  const char* stop = ScanDouble(field.data(), end, value, &status);
  if (status == NumberStatus::kOk && stop != end) return NumberStatus::kNotNumber;
  if (status == NumberStatus::kNotFinite && stop != end) return NumberStatus::kNotNumber;
  return status;
}

std::string NumberProblem(NumberStatus status, std::string_view key, std::string_view token) {
  const std::string quoted = "'" + std::string(token) + "'";
  switch (status) {
    case NumberStatus::kNotFinite:
      return std::string(key) + " must be finite, got " + quoted;
    case NumberStatus::kOutOfRange:
      return "value of " + std::string(key) + " is out of range: " + quoted;
    default:
      return "value of " + std::string(key) + " is not a number: " + quoted;
  }
}

}  // namespace calib
