#ifndef CALIB_CORE_DEFAULT_INIT_ALLOCATOR_H_
#define CALIB_CORE_DEFAULT_INIT_ALLOCATOR_H_

#include <memory>
#include <new>
#include <type_traits>
#include <utility>

namespace calib {

// std::allocator whose resize() default-initializes instead of value-initializing: a vector of a
// type whose default constructor writes nothing (scalars, fixed-size Eigen members, no default
// member initializers) then grows without writing its new elements. For long
// arrays that a parallel pass fills at once: the serial zeroing of a million elements (and its
// page faults, all on one thread) would cost more than the pass.
template <typename T>
struct DefaultInitAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() = default;
  template <typename U>
  explicit DefaultInitAllocator(const DefaultInitAllocator<U>&) {}

  template <typename U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

}  // namespace calib

#endif  // CALIB_CORE_DEFAULT_INIT_ALLOCATOR_H_
