#ifndef CALIB_TESTS_BZ2_COMPRESS_H_
#define CALIB_TESTS_BZ2_COMPRESS_H_

#include <bzlib.h>
#include <gtest/gtest.h>

#include <string>

namespace calib::testing {

// `text` as bzip2 writes it (one stream), for the readers of .bz2 logs and chunks.
inline std::string Bz2Compress(const std::string& text, int block_size_100k = 9) {
  std::string out(text.size() + text.size() / 100 + 600, '\0');
  unsigned size = static_cast<unsigned>(out.size());
  EXPECT_EQ(BZ2_bzBuffToBuffCompress(out.data(), &size, const_cast<char*>(text.data()),
                                     static_cast<unsigned>(text.size()), block_size_100k, 0, 0),
            BZ_OK);
  out.resize(size);
  return out;
}

}  // namespace calib::testing

#endif  // CALIB_TESTS_BZ2_COMPRESS_H_
