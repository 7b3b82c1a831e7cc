// After KeepFreedMemory the heap's small blocks land on 2 MB pages where the kernel gives them on
// request (/sys/kernel/mm/transparent_hugepage/enabled not "never"), and memory still works.
#include <calib/tools/process_memory.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace calib {
namespace {

bool HugePagesOnRequest() {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  return false;  // The sanitizers' allocators do not use the heap KeepFreedMemory prepares.
#else
  std::ifstream file("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string modes;
  std::getline(file, modes);
  return modes.find("[always]") != std::string::npos ||
         modes.find("[madvise]") != std::string::npos;
#endif
}

// The AnonHugePages of the mapping that holds `address`, in kB (-1 when not found).
long AnonHugePagesKbAt(const void* address) {
  const uintptr_t a = reinterpret_cast<uintptr_t>(address);
  std::ifstream smaps("/proc/self/smaps");
  std::string line;
  bool inside = false;
  while (std::getline(smaps, line)) {
    unsigned long begin = 0, end = 0;
    if (std::sscanf(line.c_str(), "%lx-%lx ", &begin, &end) == 2 && line.find(' ') > 8) {
      inside = a >= begin && a < end;
    } else if (inside && line.rfind("AnonHugePages:", 0) == 0) {
      return std::strtol(line.c_str() + std::strlen("AnonHugePages:"), nullptr, 10);
    }
  }
  return -1;
}

TEST(ProcessMemoryTest, SmallBlocksLandOnHugePagesWhereTheKernelGivesThem) {
  KeepFreedMemory();
  std::vector<char*> blocks;
  for (int i = 0; i < 4096; ++i) {  // 16 MB in blocks of 4 kB, as a calibration's vectors.
    blocks.push_back(static_cast<char*>(std::malloc(4000)));
    ASSERT_NE(blocks.back(), nullptr);
    std::memset(blocks.back(), i & 0xff, 4000);
  }
  for (int i = 0; i < 4096; i += 511) EXPECT_EQ(blocks[i][3999], static_cast<char>(i & 0xff));
  if (HugePagesOnRequest()) {
    EXPECT_GE(AnonHugePagesKbAt(blocks[2048]), 2048) << "no 2 MB page under the heap's blocks";
  }
  for (char* block : blocks) std::free(block);
}

}  // namespace
}  // namespace calib
