#include "benchmarks/bench_floor.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cstring>
#include <vector>

#include "benchmarks/bench_common.h"

namespace calib::bench {
namespace {

constexpr size_t kBufferBytes = 1 << 20;

bool StartsNumber(char c) { return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.'; }

// Streams the file; with `parse`, converts every number (a run of digits, sign, '.', 'e') and
// sums them so that nothing is optimized away. Returns false when the file cannot be read.
bool StreamFile(const std::string& path, bool parse, std::vector<char>* buffer, int64_t* bytes,
                int64_t* numbers, double* sum) {
  const int fd = open(path.c_str(), O_RDONLY);
  if (fd < 0) return false;
  size_t kept = 0;  // A number cut by the buffer's end, moved to its front.
  *bytes = *numbers = 0;
  *sum = 0;
  for (;;) {
    const ssize_t got = read(fd, buffer->data() + kept, kBufferBytes - kept);
    if (got < 0) {
      close(fd);
      return false;
    }
    *bytes += got;
    const char* p = buffer->data();
    const char* end = p + kept + got;
    if (!parse) {
      if (got == 0) break;
      continue;
    }
    while (p < end) {
      if (!StartsNumber(*p)) {
        ++p;
        continue;
      }
      const char* q = p;
      while (q < end && (StartsNumber(*q) || *q == 'e' || *q == 'E')) ++q;
      if (q == end && got != 0) break;  // May continue in the next read.
      double value = 0;
      const std::from_chars_result r = std::from_chars(p, q, value);
      if (r.ec == std::errc()) {
        *sum += value;
        ++*numbers;
      }
      p = q;
    }
    kept = static_cast<size_t>(end - p);
    std::memmove(buffer->data(), p, kept);
    if (got == 0) break;
  }
  close(fd);
  return true;
}

}  // namespace

ReadFloor MeasureReadFloor(const std::string& path, int runs) {
  ReadFloor floor;
  std::vector<char> buffer(kBufferBytes);
  double sum = 0;
  for (bool parse : {false, true}) {
    double best = -1;
    for (int run = 0; run < runs; ++run) {
      const Stopwatch watch;
      if (!StreamFile(path, parse, &buffer, &floor.bytes, &floor.numbers, &sum)) {
        return ReadFloor{};
      }
      const double s = watch.Seconds();
      if (best < 0 || s < best) best = s;
    }
    (parse ? floor.parse_s : floor.read_s) = best;
  }
  volatile double sink = sum;  // The sum is observable: the conversions are not optimized away.
  (void)sink;
  return floor;
}

}  // namespace calib::bench
