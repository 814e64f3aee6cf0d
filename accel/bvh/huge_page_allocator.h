#pragma once
// Allocator for the traversal arrays (nodes, triangle blocks): large
// allocations are aligned to 2 MiB and advised to use transparent huge pages
// (madvise(MADV_HUGEPAGE); Linux in "madvise" THP mode only backs advised
// memory with huge pages). Incoherent rays touch nodes all over a structure of
// tens of megabytes; with 4 KiB pages nearly every such access also misses the
// TLB, and under virtualisation a page walk is particularly expensive. Embree
// advises its BVH memory the same way. Small allocations use plain new.
#include <cstddef>
#include <cstdlib>
#include <new>
#include <vector>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace raylab {

inline constexpr size_t kHugePageSize = size_t{2} << 20;

template <typename T>
struct HugePageAllocator {
  using value_type = T;

  HugePageAllocator() = default;
  template <typename U>
  HugePageAllocator(const HugePageAllocator<U>&) {}

  T* allocate(size_t n) {
    const size_t bytes = n * sizeof(T);
    if (bytes >= kHugePageSize / 2) {
      const size_t rounded = (bytes + kHugePageSize - 1) / kHugePageSize * kHugePageSize;
      void* p = std::aligned_alloc(kHugePageSize, rounded);
      if (!p) throw std::bad_alloc();
#if defined(__linux__) && defined(MADV_HUGEPAGE)
      madvise(p, rounded, MADV_HUGEPAGE);  // a hint: failure only costs speed
#endif
      return static_cast<T*>(p);
    }
    return static_cast<T*>(::operator new(bytes, std::align_val_t(alignof(T) > 64 ? alignof(T) : 64)));
  }

  void deallocate(T* p, size_t n) {
    if (n * sizeof(T) >= kHugePageSize / 2) std::free(p);
    else ::operator delete(p, std::align_val_t(alignof(T) > 64 ? alignof(T) : 64));
  }

  template <typename U>
  bool operator==(const HugePageAllocator<U>&) const { return true; }
};

template <typename T>
using HugePageVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace raylab
