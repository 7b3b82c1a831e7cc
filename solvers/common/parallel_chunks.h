#ifndef CALIB_SOLVERS_COMMON_PARALLEL_CHUNKS_H_
#define CALIB_SOLVERS_COMMON_PARALLEL_CHUNKS_H_

#include <algorithm>
#include <cstddef>
#include <thread>
#include <vector>

namespace calib {

// How many chunks ParallelChunks splits n items into: at most `threads`, each of at least
// `min_chunk` items (a thread costs tens of µs to start), and at least one.
inline int ChunkCount(size_t n, int threads, size_t min_chunk) {
  return static_cast<int>(std::max<size_t>(
      1, std::min<size_t>(std::max(threads, 1), n / std::max<size_t>(1, min_chunk))));
}

// Runs body(chunk, begin, end) over [0, n) split into ChunkCount(n, threads, min_chunk)
// contiguous chunks, the first on the calling thread and the others in parallel with it.
template <typename Body>
void ParallelChunks(size_t n, int threads, size_t min_chunk, const Body& body) {
  const int chunks = ChunkCount(n, threads, min_chunk);
  std::vector<std::thread> workers;
  for (int c = 1; c < chunks; ++c) {
    workers.emplace_back(
        [&body, c, n, chunks]() { body(c, n * c / chunks, n * (c + 1) / chunks); });
  }
  body(0, 0, n / chunks);
  for (std::thread& worker : workers) worker.join();
}

}  // namespace calib

#endif  // CALIB_SOLVERS_COMMON_PARALLEL_CHUNKS_H_
