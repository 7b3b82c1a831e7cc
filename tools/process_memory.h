#ifndef CALIB_TOOLS_PROCESS_MEMORY_H_
#define CALIB_TOOLS_PROCESS_MEMORY_H_

#ifdef __GLIBC__
#include <malloc.h>
#endif

namespace calib {

// For a program's main: the timing-aware solve allocates and frees matrices of megabytes every
// round, and glibc would hand each back to the kernel and fault it in again (a tenth of a
// 10⁴-scan run, more at 10⁵). Freed memory is kept for reuse instead.
inline void KeepFreedMemory() {
#ifdef __GLIBC__
  mallopt(M_MMAP_THRESHOLD, 256 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  mallopt(M_TOP_PAD, 64 << 20);
  // One arena: the worker threads' large blocks would otherwise live in per-thread heaps that
  // are unmapped and faulted in again with every short-lived thread.
  mallopt(M_ARENA_MAX, 1);
#endif
}

}  // namespace calib

#endif  // CALIB_TOOLS_PROCESS_MEMORY_H_
