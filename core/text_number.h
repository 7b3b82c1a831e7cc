#ifndef CALIB_CORE_TEXT_NUMBER_H_
#define CALIB_CORE_TEXT_NUMBER_H_

#include <string>
#include <string_view>

// Numbers in text files: locale-free reading (std::from_chars) with finiteness checks, and the
// shortest text that reads back to the same double.
namespace calib {

// Shortest text that reads back to the same double (for messages and files).
std::string Num(double value);
void AppendGeneral(std::string* out, double value);
// Scientific like the published tuples, but the shortest form that reads back bit-exact.
void AppendScientific(std::string* out, double value);

// A UTF-8 byte-order mark some editors put first; never meaningful here.
std::string_view WithoutBom(std::string_view text);

enum class NumberStatus { kOk, kNotNumber, kNotFinite, kOutOfRange };

// Parses a double at [begin, end) and returns where it stops. from_chars also accepts
// nan/inf/Infinity, which come back as kNotFinite; an overflowing value as kOutOfRange (an
// underflow to a denormal or zero is harmless and kOk).
const char* ScanDouble(const char* begin, const char* end, double* value, NumberStatus* status);

// A finite double filling the whole of `field` (a leading '+' allowed).
NumberStatus ParseDouble(std::string_view field, double* value);

// "phi_l is not a number: 'abc'", "phi_r must be finite, got 'nan'", ...
std::string NumberProblem(NumberStatus status, std::string_view key, std::string_view token);

}  // namespace calib

#endif  // CALIB_CORE_TEXT_NUMBER_H_
