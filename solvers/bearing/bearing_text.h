#ifndef CALIB_SOLVERS_BEARING_BEARING_TEXT_H_
#define CALIB_SOLVERS_BEARING_BEARING_TEXT_H_

#include <sstream>
#include <string>

// Words shared by the bearing solvers' messages.
namespace calib {

// `value` with `digits` significant digits.
inline std::string Num(double value, int digits = 4) {
  std::ostringstream out;
  out.precision(digits);
  out << value;
  return out.str();
}

inline std::string RunName(int id) { return "run " + std::to_string(id); }

// "; " between the reasons of a list that grows.
inline void AppendReason(std::string* reasons, const std::string& reason) {
  *reasons += (reasons->empty() ? "" : "; ") + reason;
}

}  // namespace calib

#endif  // CALIB_SOLVERS_BEARING_BEARING_TEXT_H_
