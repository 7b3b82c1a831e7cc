#ifndef CALIB_CORE_TIMING_SAMPLE_CLOCK_H_
#define CALIB_CORE_TIMING_SAMPLE_CLOCK_H_

#include <vector>

// The clock of a free-running sensor: sample n is taken at t(n) = t0 + P·n + a·u², with
// u = (n − n_mid)/n_half ∈ [−1, 1] over the log, so that a (s) is the largest departure from a
// constant period (a slow drift of the sensor's oscillator), well scaled against t0 and P.
namespace calib {

struct SampleClock {
  double t0_s = 0.0;
  double period_s = 0.0;
  double drift_s = 0.0;  // a.
  double index_mid = 0.0;
  double index_half = 1.0;

  double Curvature(double n) const {
    const double u = (n - index_mid) / index_half;
    return u * u;
  }
  double Time(double n) const { return t0_s + period_s * n + drift_s * Curvature(n); }
};

// Sample indices from pick-up stamps: the sample a logger stamps at s was taken in
// (s − P, s], so n = ⌊(s − t0)/P⌋, forced strictly increasing.
std::vector<double> ClockIndicesFromStamps(const std::vector<double>& stamps_s,
                                           const SampleClock& clock);

// Least-squares t0 and P (drift 0) of times against indices; index_mid/half span the indices.
SampleClock FitSampleClock(const std::vector<double>& indices, const std::vector<double>& times_s);

// Median of the positive differences of consecutive values (0 when there are none).
double MedianStep(const std::vector<double>& values);

}  // namespace calib

#endif  // CALIB_CORE_TIMING_SAMPLE_CLOCK_H_
