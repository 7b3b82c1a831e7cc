#include <calib/core/bz2_decompress.h>
#include <gtest/gtest.h>

#include <string>

#include "tests/bz2_compress.h"

namespace calib {
namespace {

std::string Bz2(const std::string& text) { return testing::Bz2Compress(text, 1); }

std::string Text(size_t bytes) {
  std::string text;
  for (size_t k = 0; text.size() < bytes; ++k) text += std::to_string(k * 7919 % 100003) + ",";
  return text.substr(0, bytes);
}

// Two streams one after another (as pbzip2 writes), decompressed in pieces of any size.
TEST(Bz2Stream, PiecesOfSeveralStreamsMakeTheWhole) {
  const std::string a = Text(300000), b = Text(1000);
  const std::string data = Bz2(a) + Bz2(b);
  for (size_t piece : {1000, 65536, 1 << 20}) {
    std::string all;
    EXPECT_TRUE(ForEachBz2Piece(data, piece, [&](std::string_view p) {
                  EXPECT_LE(p.size(), piece);
                  all += p;
                  return Status::Ok();
                }).ok());
    EXPECT_EQ(all, a + b) << piece;
  }
  Bz2Stream one(data, false);  // A bag's chunk: the first stream only.
  std::string first;
  ASSERT_TRUE(one.Append(1 << 22, &first).ok());
  EXPECT_EQ(first, a);
  EXPECT_TRUE(one.ended());
}

// Corrupt and truncated data, and a consumer that stops early: the error comes back, and the
// decompressing thread is stopped (no hang).
TEST(Bz2Stream, ErrorsOfTheDataAndOfTheConsumerStopIt) {
  const std::string data = Bz2(Text(2000000));
  const auto read = [](std::string_view bytes) {
    return ForEachBz2Piece(bytes, 4096, [](std::string_view) { return Status::Ok(); });
  };
  EXPECT_NE(read(data.substr(0, data.size() / 2)).message().find("end before their stream does"),
            std::string::npos);
  std::string corrupt = data;
  corrupt[corrupt.size() / 2] ^= 0x55;
  EXPECT_NE(read(corrupt).message().find("corrupt"), std::string::npos);
  int calls = 0;
  const Status stopped = ForEachBz2Piece(data, 4096, [&](std::string_view) {
    return ++calls == 3 ? Status::InvalidInput("enough") : Status::Ok();
  });
  EXPECT_EQ(stopped.message(), "enough");
  EXPECT_EQ(calls, 3);
}

}  // namespace
}  // namespace calib
