#ifndef CALIB_CORE_HUGE_PAGES_H_
#define CALIB_CORE_HUGE_PAGES_H_

#include <cstddef>
#include <new>
#include <stdexcept>
#include <vector>

// Large arrays (a million intervals: ~100 MB) backed by 2 MB pages. Where the kernel gives
// transparent huge pages only on request (Debian's default, "madvise"), each 4 kB page of such an
// array costs a page fault on first touch and TLB misses on every pass; in a virtual machine both
// are slow. On the 2-core VM of the benchmark, reading 10⁶ tuples took 0.87 s with 4 kB pages and
// 0.45 s with 2 MB pages.
namespace calib {

// Asks for 2 MB pages over the whole 2 MB pages inside [data, data + bytes), before they are
// first touched. A hint: nothing happens on other systems, below 4 MB, or when the kernel says no.
void AdviseHugePages(const void* data, size_t bytes);

// Faults in the pages of [data, data + bytes) for writing without changing what they hold
// (MADV_POPULATE_WRITE, Linux 5.14): safe while other threads use the memory, so that a helper
// thread can pay the faults (and the zeroing of 2 MB pages) ahead of the threads that will write
// there. Returns false where the kernel does not offer it (nothing happens then).
bool PopulateForWriting(void* data, size_t bytes);

// v->reserve(n) with the new storage advised as above. An estimate that asks for more memory than
// there is leaves the vector to grow as its elements come.
template <typename T, typename Allocator>
void ReserveOnHugePages(std::vector<T, Allocator>* v, size_t n) {
  if (n <= v->capacity()) return;
  try {
    v->reserve(n);
  } catch (const std::bad_alloc&) {
    return;
  } catch (const std::length_error&) {
    return;
  }
  AdviseHugePages(v->data() + v->size(), (v->capacity() - v->size()) * sizeof(T));
}

// Memory of its own mapping, given back to the kernel when freed, wherever malloc keeps freed
// blocks for reuse (tools/process_memory.h): for a large temporary that would otherwise leave a
// hole in the heap that later, larger blocks cannot use. Advised as above.
void* MapMemory(size_t bytes);  // Throws std::bad_alloc.
void UnmapMemory(void* data, size_t bytes);

template <typename T>
struct MappedAllocator {
  using value_type = T;
  MappedAllocator() = default;
  template <typename U>
  explicit MappedAllocator(const MappedAllocator<U>&) {}
  T* allocate(size_t n) {
    if (n > static_cast<size_t>(-1) / sizeof(T)) throw std::bad_alloc();
    return static_cast<T*>(MapMemory(n * sizeof(T)));
  }
  void deallocate(T* data, size_t n) { UnmapMemory(data, n * sizeof(T)); }
  bool operator==(const MappedAllocator&) const { return true; }
  bool operator!=(const MappedAllocator&) const { return false; }
};

}  // namespace calib

#endif  // CALIB_CORE_HUGE_PAGES_H_
