#include <calib/core/huge_pages.h>

#include <cstdint>
#include <cstdlib>
#include <new>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace calib {

void AdviseHugePages(const void* data, size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  constexpr uintptr_t kHugePage = uintptr_t{1} << 21;
  if (data == nullptr || bytes < 2 * kHugePage) return;
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(data) + kHugePage - 1) & ~(kHugePage - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(data) + bytes) & ~(kHugePage - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
  (void)data;
  (void)bytes;
#endif
}

bool PopulateForWriting(void* data, size_t bytes) {
#if defined(__linux__)
  constexpr int kPopulateWrite = 23;  // MADV_POPULATE_WRITE, absent from older headers.
  return data != nullptr && madvise(data, bytes, kPopulateWrite) == 0;
#else
  (void)data;
  (void)bytes;
  return false;
#endif
}

void* MapMemory(size_t bytes) {
  if (bytes == 0) bytes = 1;
#if defined(__linux__)
  void* data = mmap(nullptr, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (data == MAP_FAILED) throw std::bad_alloc();
  AdviseHugePages(data, bytes);
  return data;
#else
  void* data = std::malloc(bytes);
  if (data == nullptr) throw std::bad_alloc();
  return data;
#endif
}

void UnmapMemory(void* data, size_t bytes) {
  if (data == nullptr) return;
#if defined(__linux__)
  munmap(data, bytes == 0 ? 1 : bytes);
#else
  (void)bytes;
  std::free(data);
#endif
}

}  // namespace calib
