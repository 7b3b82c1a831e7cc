#ifndef CALIB_CORE_TIMING_STAMP_TIMING_INTERNAL_H_
#define CALIB_CORE_TIMING_STAMP_TIMING_INTERNAL_H_

#include <calib/core/timing/stamp_timing.h>

#include <vector>

// Pieces shared by stamp_timing.cc and stamp_timing_verdict.cc; not part of the API.
namespace calib::timing_internal {

// The median (mean of the two middle values for an even count); 0 for an empty vector.
double Median(std::vector<double> values);

// Whether the w steps d[0..w) are whole multiples k (0..4, |d/u − k| ≤ tolerance) of one unit
// u > 0, every zero isolated inside the window and followed by k ≥ 2; fills k_of.
bool SteadyWindow(const double* d, int w, double tolerance, std::vector<int>* k_of);

// Sets regular, free_running_signature and stamps_are_sample_times from the figures and writes
// the notes.
void Conclude(StreamTiming* timing);

}  // namespace calib::timing_internal

#endif  // CALIB_CORE_TIMING_STAMP_TIMING_INTERNAL_H_
