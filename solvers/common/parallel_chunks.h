#ifndef CALIB_SOLVERS_COMMON_PARALLEL_CHUNKS_H_
#define CALIB_SOLVERS_COMMON_PARALLEL_CHUNKS_H_

#include <algorithm>
#include <cstddef>

namespace calib {

// How many chunks ParallelChunks splits n items into: at most `threads`, each of at least
// `min_chunk` items, and at least one.
inline int ChunkCount(size_t n, int threads, size_t min_chunk) {
  return static_cast<int>(std::max<size_t>(
      1, std::min<size_t>(std::max(threads, 1), n / std::max<size_t>(1, min_chunk))));
}

// How many chunks ParallelSplit splits n items into: each of at least `min_chunk` items, at most
// kMaxSplit, at least one; whatever the number of threads.
constexpr int kMaxSplit = 8;
inline int SplitCount(size_t n, size_t min_chunk) {
  return static_cast<int>(
      std::max<size_t>(1, std::min<size_t>(kMaxSplit, n / std::max<size_t>(1, min_chunk))));
}

namespace parallel_internal {

// Runs run(context, c) for every c in [0, chunks): the calling thread claims chunks in turn with
// up to threads − 1 helper threads that wait between passes (started once, never torn down), so a
// pass costs a wake-up, not a thread start. The caller does all chunks itself when no helper is
// free (another thread's pass holds them, a pass nested in a chunk, or OccupiedCore).
void RunChunks(int chunks, int threads, void (*run)(const void* context, int chunk),
               const void* context);

// body(chunk, begin, end) over [0, n) in `chunks` contiguous chunks.
template <typename Body>
void RunSplit(size_t n, int chunks, int threads, const Body& body) {
  if (chunks == 1) {
    body(0, size_t{0}, n);
    return;
  }
  struct Context {
    const Body* body;
    size_t n;
    int chunks;
  } context{&body, n, chunks};
  RunChunks(
      chunks, threads,
      [](const void* p, int c) {
        const Context& x = *static_cast<const Context*>(p);
        (*x.body)(c, x.n * c / x.chunks, x.n * (c + 1) / x.chunks);
      },
      &context);
}

}  // namespace parallel_internal

// While one lives, a thread of the process is busy with other work than these passes (a model
// screen beside the calibration): one helper fewer joins them. On two cores a helper would only
// take that thread's core (or, woken beside its caller, the caller's), and the pass would wait
// for the chunks it holds.
class OccupiedCore {
 public:
  OccupiedCore();
  ~OccupiedCore();
  OccupiedCore(const OccupiedCore&) = delete;
  OccupiedCore& operator=(const OccupiedCore&) = delete;
};

// Runs body(chunk, begin, end) over [0, n) split into ChunkCount(n, threads, min_chunk)
// contiguous chunks, the calling thread and idle helpers each taking the next chunk.
template <typename Body>
void ParallelChunks(size_t n, int threads, size_t min_chunk, const Body& body) {
  parallel_internal::RunSplit(n, ChunkCount(n, threads, min_chunk), threads, body);
}

// The same over SplitCount(n, min_chunk) chunks: the split does not depend on the threads nor on
// which thread ran a chunk, so per-chunk partial sums added in chunk order give the same figures
// on one thread as on several.
template <typename Body>
void ParallelSplit(size_t n, int threads, size_t min_chunk, const Body& body) {
  parallel_internal::RunSplit(n, SplitCount(n, min_chunk), threads, body);
}

}  // namespace calib

#endif  // CALIB_SOLVERS_COMMON_PARALLEL_CHUNKS_H_
