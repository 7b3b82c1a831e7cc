#ifndef CALIB_CORE_RANDOM_H_
#define CALIB_CORE_RANDOM_H_

#include <cmath>
#include <cstdint>
#include <random>

// Random numbers for the simulators built only on raw std::mt19937_64 output, whose sequence
// the standard fixes, so that a seed gives the same log with any standard library
// (std::normal_distribution and friends are implementation-defined).
namespace calib {

class Random {
 public:
  // The engine seeded with `seed` itself (as std::mt19937_64(seed)).
  explicit Random(uint64_t seed) : engine_(seed) {}
  // An independent stream per purpose: the engine seeded from (seed, stream) via seed_seq.
  Random(uint64_t seed, uint32_t stream) {
    std::seed_seq sequence{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32), stream};
    engine_.seed(sequence);
  }

  // Uniform in [0, 1) with 53 random bits.
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  double Sign() { return (engine_() >> 63) != 0 ? 1.0 : -1.0; }
  // Uniform in [0, n); the modulo bias is below n / 2^64.
  uint64_t Index(uint64_t n) { return engine_() % n; }
  double Exponential(double mean) { return -mean * std::log1p(-Uniform()); }

  // Standard normal by Box–Muller on Uniform(); the second variate of each pair is kept for the
  // next call. (The laser simulator's; its committed logs depend on this sequence.)
  double Normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    const double radius = std::sqrt(-2.0 * std::log(1.0 - Uniform()));  // 1 − U is in (0, 1].
    const double angle = 2.0 * M_PI * Uniform();
    spare_ = radius * std::sin(angle);
    has_spare_ = true;
    return radius * std::cos(angle);
  }

  // Standard normal by Marsaglia's polar method on Canonical(), the second variate of each pair
  // kept for the next call: bit for bit the sequence of libstdc++'s
  // std::normal_distribution<double> on the same engine, here with any standard library. (The
  // bearing simulator's; its committed logs depend on this sequence.)
  double NormalPolar() {
    if (has_polar_spare_) {
      has_polar_spare_ = false;
      return polar_spare_;
    }
    double x, y, r2;
    do {
      x = 2.0 * Canonical() - 1.0;
      y = 2.0 * Canonical() - 1.0;
      r2 = x * x + y * y;
    } while (r2 > 1.0 || r2 == 0.0);
    const double mult = std::sqrt(-2.0 * std::log(r2) / r2);
    polar_spare_ = x * mult;
    has_polar_spare_ = true;
    return y * mult;
  }

  // Uniform in [0, 1) as std::generate_canonical<double, 53> computes it from one 64-bit draw:
  // the draw rounded to double over 2^64, and just below 1 where that rounds up to 1.
  double Canonical() {
    const double u = static_cast<double>(engine_()) / 0x1.0p64;
    return u < 1.0 ? u : std::nextafter(1.0, 0.0);
  }

 private:
  std::mt19937_64 engine_;
  bool has_spare_ = false;
  double spare_ = 0.0;
  bool has_polar_spare_ = false;
  double polar_spare_ = 0.0;
};

}  // namespace calib

#endif  // CALIB_CORE_RANDOM_H_
