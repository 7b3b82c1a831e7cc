#ifndef CALIB_CORE_ENCODER_SPIKES_H_
#define CALIB_CORE_ENCODER_SPIKES_H_

#include <calib/core/encoder_sample.h>

#include <string>
#include <vector>

// Cumulative wheel angles that jump away and come back: one logged value of 1000 rad (or 1e300)
// among angles that move by milliradians per sample. Taken as given, the glitch is a burst of
// wheel travel that no calibration explains. A sample is a spike when a finite value is beyond 1e9,
// or when the steps into and out of it are opposite and both more than 1000 times the stream's own
// step scale (the (m+1)-th largest step, m = max(4, n/25), so that a few spikes cannot raise the
// scale they are judged by).
namespace calib {

// True for each spike. Empty (no spikes) when more than max(2, n/50) samples look like spikes:
// that many are the stream's nature or unit, not glitches, and are left to the checks after.
std::vector<bool> FindEncoderSpikes(const std::vector<EncoderSample>& samples);

// Removes the spikes from `samples`; returns how many, and the first one's line in `first_line`.
int DropEncoderSpikes(std::vector<EncoderSample>* samples, int* first_line);

}  // namespace calib

#endif  // CALIB_CORE_ENCODER_SPIKES_H_
