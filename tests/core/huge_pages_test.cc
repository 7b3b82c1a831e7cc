// Reserving on huge pages is a hint: the vector behaves as after reserve(), keeps its elements,
// and an estimate beyond any memory leaves it as it was. Populating keeps the contents.
#include <calib/core/huge_pages.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

namespace calib {
namespace {

TEST(HugePagesTest, ReservesKeepsTheElementsAndSurvivesAbsurdEstimates) {
  std::vector<double> v = {1.0, 2.0, 3.0};
  const size_t n = (size_t{16} << 20) / sizeof(double);  // 16 MB: whole 2 MB pages inside.
  ReserveOnHugePages(&v, n);
  ASSERT_GE(v.capacity(), n);
  EXPECT_EQ(v, (std::vector<double>{1.0, 2.0, 3.0}));
  const double* data = v.data();
  v.resize(n, 4.0);  // Touched after the advice; no reallocation.
  EXPECT_EQ(v.data(), data);
  EXPECT_EQ(v[2], 3.0);
  EXPECT_EQ(v.back(), 4.0);

  ReserveOnHugePages(&v, 10);  // Enough already: nothing changes.
  EXPECT_EQ(v.data(), data);

  std::vector<int64_t> w = {7};
  ReserveOnHugePages(&w, std::numeric_limits<size_t>::max() / 4);   // length_error inside.
  ReserveOnHugePages(&w, std::numeric_limits<size_t>::max() / 16);  // bad_alloc inside.
  EXPECT_EQ(w, (std::vector<int64_t>{7}));

  // Ranges too short for a whole huge page, or none at all, are left alone.
  AdviseHugePages(nullptr, size_t{1} << 30);
  AdviseHugePages(w.data(), sizeof(int64_t));
}

#if defined(__linux__)
// Populated pages are resident and keep what was written before, whichever thread writes next.
TEST(HugePagesTest, PopulatingKeepsTheContentsAndMakesThePagesResident) {
  const size_t page = static_cast<size_t>(sysconf(_SC_PAGESIZE));
  const size_t bytes = 64 * page;
  void* mapped = MapMemory(bytes);
  unsigned char* data = static_cast<unsigned char*>(mapped);
  for (size_t i = 0; i < bytes; i += 3 * page) data[i + 1] = static_cast<unsigned char>(i / page);
  if (!PopulateForWriting(mapped, bytes)) {
    UnmapMemory(mapped, bytes);
    GTEST_SKIP() << "the kernel does not offer MADV_POPULATE_WRITE";
  }
  std::vector<unsigned char> resident(64);
  ASSERT_EQ(mincore(mapped, bytes, resident.data()), 0);
  for (size_t p = 0; p < 64; ++p) EXPECT_TRUE(resident[p] & 1) << "page " << p;
  for (size_t i = 0; i < bytes; i += page) {
    EXPECT_EQ(data[i + 1], i % (3 * page) == 0 ? static_cast<unsigned char>(i / page) : 0);
  }
  UnmapMemory(mapped, bytes);
  EXPECT_FALSE(PopulateForWriting(nullptr, bytes));
}
#endif

}  // namespace
}  // namespace calib
