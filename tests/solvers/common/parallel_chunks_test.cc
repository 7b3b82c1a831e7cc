#include <calib/solvers/common/parallel_chunks.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <memory>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

namespace calib {
namespace {

// Per-chunk sums of sin(k) over [0, n), added in chunk order.
double ChunkedSum(size_t n, int threads, size_t min_chunk) {
  std::vector<double> parts(SplitCount(n, min_chunk), 0.0);
  ParallelSplit(n, threads, min_chunk, [&](size_t chunk, size_t begin, size_t end) {
    double sum = 0.0;
    for (size_t k = begin; k < end; ++k) sum += std::sin(static_cast<double>(k));
    parts[chunk] = sum;
  });
  double total = 0.0;
  for (double p : parts) total += p;
  return total;
}

TEST(ParallelChunksTest, EveryItemOnceInContiguousChunks) {
  for (const int threads : {1, 2, 4}) {
    for (const size_t n : {size_t{0}, size_t{1}, size_t{999}, size_t{4096}, size_t{100003}}) {
      std::vector<std::atomic<int>> seen(n);
      std::mutex mutex;
      std::set<std::pair<size_t, size_t>> ranges;
      ParallelSplit(n, threads, 100, [&](size_t, size_t begin, size_t end) {
        for (size_t k = begin; k < end; ++k) seen[k].fetch_add(1);
        std::lock_guard<std::mutex> lock(mutex);
        ranges.insert({begin, end});
      });
      for (size_t k = 0; k < n; ++k) ASSERT_EQ(seen[k].load(), 1) << "item " << k;
      EXPECT_EQ(ranges.size(), static_cast<size_t>(SplitCount(n, 100)));
      size_t next = 0;
      for (const auto& [begin, end] : ranges) {
        EXPECT_EQ(begin, next);
        next = end;
      }
      EXPECT_EQ(next, n);
    }
  }
}

// The split does not depend on the threads: the same sums, bit for bit, on one thread or several,
// however the chunks fell to the threads.
TEST(ParallelChunksTest, SplitSumsDoNotDependOnTheThreads) {
  const double one = ChunkedSum(50000, 1, 500);
  for (int run = 0; run < 20; ++run) {
    EXPECT_EQ(ChunkedSum(50000, 2, 500), one);
    EXPECT_EQ(ChunkedSum(50000, 8, 500), one);
  }
  EXPECT_EQ(SplitCount(50000, 500), kMaxSplit);
  EXPECT_EQ(SplitCount(1200, 500), 2);
  EXPECT_EQ(SplitCount(10, 500), 1);
}

// A pass inside a chunk, and passes from two threads at once, run (the helpers serve one pass;
// the others run on their callers) and give every item once.
TEST(ParallelChunksTest, NestedAndConcurrentPassesComplete) {
  std::atomic<long> total{0};
  const auto outer = [&] {
    ParallelSplit(16000, 2, 1000, [&](size_t, size_t begin, size_t end) {
      ParallelChunks(end - begin, 2, 10, [&](size_t, size_t b, size_t e) {
        total.fetch_add(static_cast<long>(e - b));
      });
    });
  };
  std::thread other([&] {
    for (int i = 0; i < 50; ++i) outer();
  });
  for (int i = 0; i < 50; ++i) outer();
  other.join();
  EXPECT_EQ(total.load(), 100L * 16000L);
}

// With every other core occupied, a pass runs on its caller alone.
TEST(ParallelChunksTest, OccupiedCoresLeaveThePassToItsCaller) {
  const unsigned cores = std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::unique_ptr<OccupiedCore>> occupied;
  for (unsigned c = 1; c < cores; ++c) occupied.push_back(std::make_unique<OccupiedCore>());
  const std::thread::id caller = std::this_thread::get_id();
  std::atomic<int> elsewhere{0};
  for (int run = 0; run < 20; ++run) {
    ParallelSplit(8000, 4, 100, [&](size_t, size_t, size_t) {
      if (std::this_thread::get_id() != caller) elsewhere.fetch_add(1);
    });
  }
  EXPECT_EQ(elsewhere.load(), 0);
  occupied.clear();
  EXPECT_EQ(ChunkedSum(50000, 2, 500), ChunkedSum(50000, 1, 500));
}

}  // namespace
}  // namespace calib
