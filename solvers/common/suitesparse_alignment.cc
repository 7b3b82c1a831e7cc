#include <calib/solvers/common/suitesparse_alignment.h>
#include <malloc.h>
#include <suitesparse/SuiteSparse_config.h>

#include <cstdlib>
#include <cstring>

namespace calib {
namespace {

constexpr size_t kAlignment = 64;

// aligned_alloc wants a multiple of the alignment; 0 bytes still gets a block.
void* AlignedMalloc(size_t bytes) {
  const size_t rounded = (bytes + kAlignment - 1) / kAlignment * kAlignment;
  if (rounded < bytes) return nullptr;
  return std::aligned_alloc(kAlignment, rounded == 0 ? kAlignment : rounded);
}

void* AlignedCalloc(size_t count, size_t size) {
  if (size != 0 && count > static_cast<size_t>(-1) / size) return nullptr;
  void* block = AlignedMalloc(count * size);
  if (block != nullptr) std::memset(block, 0, count * size);
  return block;
}

// Also for blocks that the plain malloc gave (before the switch).
void* AlignedRealloc(void* block, size_t bytes) {
  if (block == nullptr) return AlignedMalloc(bytes);
  void* moved = AlignedMalloc(bytes);
  if (moved == nullptr) return nullptr;  // SuiteSparse keeps the old block.
  const size_t old_bytes = malloc_usable_size(block);
  std::memcpy(moved, block, old_bytes < bytes ? old_bytes : bytes);
  std::free(block);
  return moved;
}

}  // namespace

void AlignSuiteSparseAllocations() {
  static const bool done = [] {
    SuiteSparse_config.malloc_func = AlignedMalloc;
    SuiteSparse_config.calloc_func = AlignedCalloc;
    SuiteSparse_config.realloc_func = AlignedRealloc;
    return true;
  }();
  (void)done;
}

}  // namespace calib
