#include <calib/core/random.h>
#include <calib/core/text_format.h>
#include <calib/core/text_number.h>
#include <gtest/gtest.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

namespace calib {
namespace {

TEST(TextFormatTest, FormatsLikePrintfAndCutsAtItsLimit) {
  EXPECT_EQ(Format("%d/%d = %.1f%%", 1, 4, 25.0), "1/4 = 25.0%");
  EXPECT_EQ(Format("<text x='%.1f'>%s</text>", 2.25, "a"), "<text x='2.2'>a</text>");
  EXPECT_EQ(Format("%s", std::string(600, 'x').c_str()).size(), 511u);
}

// ScanDouble reads what from_chars reads, to the bit and to the character: the logs' own formats
// (%.6e, %.9g, %.17g, %f, the shortest round trip), short and long mantissas (around 2^53 and
// 2^64), large exponents, signed zeros, and text around or inside a number.
TEST(TextNumberTest, ScanDoubleReadsWhatFromCharsReads) {
  std::vector<std::string> tokens = {
      "0", "-0", "-0.0e5", "5.", ".5", "1e5x", "1e+", "1e-x", "2E3", "7e-22", "7e-23", "3e22",
      "3e23", "0e999", "1e400", "1e-400", "nan", "-inf", "Inf", "0x1p3", "-", ".", "abc", "12,5",
      "1.5e+07 ", "123456789012345", "1234567890123456", "9007199254740992", "9007199254740993",
      "-9.007199254740993e-5", "9.007199254740992e22", "1234567890123456789",
      "12345678901234567890", "0.000000000000000000009007199254740991", "18446744073709551616",
      "0.000000000000000000001234", "999999999999999e22", "000000000000000000000000123",
      "1.7976931348623157e308",
      // Eight digits at a time: leading zeros, long fractions.
      "0.00000000123456789", "0.0000000000000000123456789012", "-0.12345678901234567890",
      "1.00000000000000000001", "12345678.12345678", "1.2345678", "1.23456789e-3",
      "0.000000000000000000000000001e30"};
  Random random(3);
  char buffer[64];
  for (int i = 0; i < 20000; ++i) {
    const double value =
        std::ldexp(random.Uniform(-1.0, 1.0), static_cast<int>(random.Index(200)) - 100);
    const char* formats[] = {"%.6e", "%.9g", "%.17g", "%f", "%.3f", "%.15e", "%.16e"};
    if (i % 8 == 7) {  // The shortest round trip (calib's own writers): 15 to 17 digits.
      const auto written =
          std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::scientific);
      tokens.emplace_back(buffer, written.ptr);
    } else {
      std::snprintf(buffer, sizeof(buffer), formats[i % 8], value);
      tokens.push_back(buffer);
    }
  }
  for (const std::string& token : tokens) {
    const char* begin = token.data();
    const char* end = begin + token.size();
    double expected = 0.0, got = 0.0;
    const auto want = std::from_chars(begin, end, expected);
    NumberStatus status;
    const char* stop = ScanDouble(begin, end, &got, &status);
    if (want.ec == std::errc::invalid_argument) {
      EXPECT_EQ(status, NumberStatus::kNotNumber) << token;
      continue;
    }
    EXPECT_EQ(stop, want.ptr) << token;
    if (want.ec == std::errc() && std::isfinite(expected)) {
      EXPECT_EQ(status, NumberStatus::kOk) << token;
      EXPECT_EQ(std::memcmp(&got, &expected, sizeof got), 0)
          << token << ": " << got << " vs " << expected;
    }
  }
}

}  // namespace
}  // namespace calib
