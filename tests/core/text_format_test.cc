#include <calib/core/text_format.h>
#include <gtest/gtest.h>

#include <string>

namespace calib {
namespace {

TEST(TextFormatTest, FormatsLikePrintfAndCutsAtItsLimit) {
  EXPECT_EQ(Format("%d/%d = %.1f%%", 1, 4, 25.0), "1/4 = 25.0%");
  EXPECT_EQ(Format("<text x='%.1f'>%s</text>", 2.25, "a"), "<text x='2.2'>a</text>");
  EXPECT_EQ(Format("%s", std::string(600, 'x').c_str()).size(), 511u);
}

}  // namespace
}  // namespace calib
