// Reserving on huge pages is a hint: the vector behaves as after reserve(), keeps its elements,
// and an estimate beyond any memory leaves it as it was.
#include <calib/core/huge_pages.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <vector>

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

}  // namespace
}  // namespace calib
