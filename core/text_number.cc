#include <calib/core/text_number.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
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

namespace {

// Whether the 8 bytes at p are all digits; if so, their value (SWAR, as in fast_float).
bool EightDigits(const char* p, const char* end, uint64_t* value) {
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
  if (end - p < 8) return false;
  uint64_t v;
  std::memcpy(&v, p, 8);  // Little-endian: the first digit in the lowest byte.
  if (((v & 0xF0F0F0F0F0F0F0F0) | (((v + 0x0606060606060606) & 0xF0F0F0F0F0F0F0F0) >> 4)) !=
      0x3333333333333333) {
    return false;
  }
  v -= 0x3030303030303030;
  v = (v * 10) + (v >> 8);  // Pairs.
  v = (((v & 0x000000FF000000FF) * 0x000F424000000064) +
       (((v >> 16) & 0x000000FF000000FF) * 0x0000271000000001)) >>
      32;
  *value = static_cast<uint32_t>(v);
  return true;
#else
  (void)p, (void)end, (void)value;
  return false;  // Digit by digit.
#endif
}

// The digits of a value below 10^8 from its first nonzero one (0 for 0).
int SignificantDigits(uint64_t v) {
  int n = 0;
  for (; v > 0; v /= 10) ++n;
  return n;
}

// Clinger's fast path: a decimal whose digits form an integer m ≤ 2^53 (exact as a double: any
// 15 significant digits, most 16) times a power of ten within 10^±22 is one correctly rounded
// operation on exact doubles, so it is from_chars' value (logs write their numbers so: %.6e,
// %.9g, and the round trip's 16 digits half the time), at a fifth of its time. Null for anything
// else (a larger m, from 20 significant digits on as soon as it is seen; a larger exponent, inf,
// nan, no digits): from_chars then reads it.
const char* ScanShortDecimal(const char* p, const char* end, double* value) {
  static constexpr double kPowers[] = {1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                       1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15,
                                       1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};
  const auto digit = [&](const char* q) { return q < end && *q >= '0' && *q <= '9'; };
  const bool negative = p < end && *p == '-';
  if (negative) ++p;
  constexpr int kMaxSignificant = 19;  // 10^19 − 1 < 2^64: m cannot overflow.
  constexpr uint64_t kLargestExact = uint64_t{1} << 53;
  uint64_t mantissa = 0;
  int significant = 0, exponent = 0, digits = 0;
  for (; digit(p); ++p, ++digits) {
    mantissa = 10 * mantissa + static_cast<uint64_t>(*p - '0');
    significant += significant > 0 || *p != '0';  // From the first nonzero digit on.
    if (significant > kMaxSignificant) return nullptr;
  }
  if (p < end && *p == '.') {
    ++p;
    // Eight fraction digits at a time while m stays below 10^19 (the same m as digit by digit).
    uint64_t eight;
    while (significant <= kMaxSignificant - 8 && EightDigits(p, end, &eight)) {
      const int added = significant > 0 ? 8 : SignificantDigits(eight);
      mantissa = 100000000 * mantissa + eight;
      significant += added;
      p += 8, digits += 8, exponent -= 8;
    }
    for (; digit(p); ++p, ++digits, --exponent) {
      mantissa = 10 * mantissa + static_cast<uint64_t>(*p - '0');
      significant += significant > 0 || *p != '0';  // From the first nonzero digit on.
      if (significant > kMaxSignificant) return nullptr;
    }
  }
  if (digits == 0 || mantissa > kLargestExact) return nullptr;
  if (p < end && (*p == 'e' || *p == 'E')) {
    const char* q = p + 1;
    const bool negative_exponent = q < end && *q == '-';
    if (q < end && (*q == '-' || *q == '+')) ++q;
    if (digit(q)) {  // Else the number ends before the 'e', as from_chars reads it.
      int written = 0;
      for (; digit(q) && written < 1000; ++q) written = 10 * written + (*q - '0');
      if (digit(q)) return nullptr;
      exponent += negative_exponent ? -written : written;
      p = q;
    }
  }
  double v = static_cast<double>(mantissa);
  if (mantissa != 0) {
    if (exponent < -22 || exponent > 22) return nullptr;
    v = exponent < 0 ? v / kPowers[-exponent] : v * kPowers[exponent];
  }
  *value = negative ? -v : v;
  return p;
}

}  // namespace

const char* ScanDouble(const char* begin, const char* end, double* value, NumberStatus* status) {
  if (const char* stop = ScanShortDecimal(begin, end, value)) {
    *status = NumberStatus::kOk;
    return stop;
  }
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
