#include <calib/core/encoder_spikes.h>
#include <gtest/gtest.h>

namespace calib {
namespace {

std::vector<EncoderSample> Ramp(int n) {
  std::vector<EncoderSample> samples;
  for (int k = 0; k < n; ++k) {
    samples.push_back(EncoderSample{0.02 * k, 0.01 * k + 0.001 * (k % 3), 0.012 * k, k + 2});
  }
  return samples;
}

TEST(EncoderSpikesTest, SmoothAnglesHaveNone) {
  std::vector<EncoderSample> samples = Ramp(500);
  EXPECT_EQ(DropEncoderSpikes(&samples, nullptr), 0);
  EXPECT_EQ(samples.size(), 500u);
}

TEST(EncoderSpikesTest, JumpAwayAndBackIsDropped) {
  std::vector<EncoderSample> samples = Ramp(500);
  samples[100].left_rad = 1000.0;
  samples[300].right_rad = 1e300;
  int first_line = 0;
  EXPECT_EQ(DropEncoderSpikes(&samples, &first_line), 2);
  EXPECT_EQ(first_line, 102);
  EXPECT_EQ(samples.size(), 498u);
}

// A wheel that really turns fast for a while is no spike: the steps do not come back.
TEST(EncoderSpikesTest, LastingJumpIsKept) {
  std::vector<EncoderSample> samples = Ramp(500);
  for (size_t k = 200; k < samples.size(); ++k) samples[k].left_rad += 1000.0;
  EXPECT_EQ(DropEncoderSpikes(&samples, nullptr), 0);
}

// Many spike-like samples are the stream's nature, not glitches.
TEST(EncoderSpikesTest, ManyAreKept) {
  std::vector<EncoderSample> samples = Ramp(100);
  for (size_t k = 1; k < 99; k += 3) samples[k].left_rad = 1000.0;
  EXPECT_EQ(DropEncoderSpikes(&samples, nullptr), 0);
}

}  // namespace
}  // namespace calib
