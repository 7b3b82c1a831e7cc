#ifndef CALIB_TOOLS_PROCESS_MEMORY_H_
#define CALIB_TOOLS_PROCESS_MEMORY_H_

#include <calib/core/huge_pages.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <system_error>
#include <thread>

#ifdef __GLIBC__
#include <malloc.h>
#include <unistd.h>
#endif

namespace calib {

// For a program's main: the timing-aware solve allocates and frees matrices of megabytes every
// round, and glibc would hand each back to the kernel and fault it in again (a tenth of a
// 10⁴-scan run, more at 10⁵). Freed memory is kept for reuse instead.
//
// The heap also grows by 64 MB at once, advised for 2 MB pages (core/huge_pages.h): a run on a
// real set touched ~1900 fresh 4 kB pages, ~1000 of them heap, and on the benchmark's VM the
// faults cost about a sixth of the run (l90: 1900 → 550 faults, 60 → 51 ms).
inline void KeepFreedMemory() {
#ifdef __GLIBC__
  constexpr size_t kTopPad = size_t{64} << 20;
  mallopt(M_MMAP_THRESHOLD, 256 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  mallopt(M_TOP_PAD, static_cast<int>(kTopPad));
  // One arena: the worker threads' large blocks would otherwise live in per-thread heaps that
  // are unmapped and faulted in again with every short-lived thread.
  mallopt(M_ARENA_MAX, 1);
#if __GLIBC__ > 2 || __GLIBC_MINOR__ >= 33
  // A block just larger than the heap's free top makes malloc grow the heap now. Growing writes
  // the new top's header behind the block, and a 2 MB region with a 4 kB page already in it can
  // no longer get a 2 MB page: advice starts after that page.
  const size_t top = mallinfo2().keepcost;
  const uintptr_t brk_before = reinterpret_cast<uintptr_t>(sbrk(0));
  void* block = std::malloc(top + 4096);
  const uintptr_t brk_after = reinterpret_cast<uintptr_t>(sbrk(0));
  const uintptr_t start = reinterpret_cast<uintptr_t>(block), header = start + top + 4096;
  std::free(block);
  constexpr uintptr_t kHugePage = uintptr_t{1} << 21;
  const uintptr_t advised = (header + 64 + kHugePage - 1) & ~(kHugePage - 1);
  // Only where the block came from the heap's top (not a sanitizer's or another allocator's).
  if (start == 0 || brk_after <= brk_before || advised >= brk_after ||
      brk_after - advised > 2 * kTopPad) {
    return;
  }
  AdviseHugePages(reinterpret_cast<void*>(advised), brk_after - advised);
  // The first blocks' faults (a real set's run fills ~8 MB of heap; each 2 MB page is zeroed on
  // its first touch) are paid on another thread while the program reads its flags and input: on
  // the benchmark's VM the real sets' median run went from 23–27 to 18–23 ms. One page per call:
  // a call holds the address space's lock, and the main thread's mappings (of the input, of
  // the threads' stacks) wait for it, for ~0.4 ms a page rather than ~2 ms for all four.
  constexpr size_t kPrefault = size_t{8} << 20;
  try {
    std::thread([advised, bytes = std::min<size_t>(kPrefault, brk_after - advised), kHugePage] {
      for (size_t at = 0; at < bytes; at += kHugePage) {
        PopulateForWriting(reinterpret_cast<void*>(advised + at), std::min(kHugePage, bytes - at));
      }
    }).detach();
  } catch (const std::system_error&) {  // No thread to be had: the faults come as they come.
  }
  // The spoilt region before the advice stays unused (address space only), so that the blocks
  // to come start on 2 MB pages.
  static void* const spoilt = std::malloc(advised - start - 64);
  (void)spoilt;
#endif
#endif
}

}  // namespace calib

#endif  // CALIB_TOOLS_PROCESS_MEMORY_H_
