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
#include <type_traits>
#include <utility>
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

// HugePageAllocator whose vectors default-initialise: resize() leaves trivial
// elements unwritten (and their pages untouched) instead of zeroing them, for
// arrays a builder sizes for the worst case and writes in part (every element
// below the final size must be written before it is read).
template <typename T>
struct UninitHugePageAllocator : HugePageAllocator<T> {
  template <typename U>
  struct rebind {
    using other = UninitHugePageAllocator<U>;
  };
  UninitHugePageAllocator() = default;
  template <typename U>
  UninitHugePageAllocator(const UninitHugePageAllocator<U>&) {}

  template <typename U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};

template <typename T>
using UninitHugePageVector = std::vector<T, UninitHugePageAllocator<T>>;

// Uninitialised storage for n objects from HugePageAllocator, for the
// builders' large temporary tables whose every element is written before it
// is read: a vector would first fill them, and with 4 KiB pages the first
// touch of tens of megabytes costs thousands of page faults (perf: a fifth
// of a single-threaded BVH build was page faults).
template <typename T>
class HugePageBuffer {
  static_assert(std::is_trivially_copyable_v<T> && std::is_trivially_destructible_v<T>);

 public:
  HugePageBuffer() = default;
  explicit HugePageBuffer(size_t n) : data_(n ? HugePageAllocator<T>().allocate(n) : nullptr), size_(n) {}
  HugePageBuffer(const HugePageBuffer&) = delete;
  HugePageBuffer& operator=(const HugePageBuffer&) = delete;
  HugePageBuffer(HugePageBuffer&& o) noexcept { swap(o); }
  HugePageBuffer& operator=(HugePageBuffer&& o) noexcept {
    swap(o);
    return *this;
  }
  ~HugePageBuffer() {
    if (data_) HugePageAllocator<T>().deallocate(data_, size_);
  }

  T* data() { return data_; }
  const T* data() const { return data_; }
  size_t size() const { return size_; }
  T& operator[](size_t i) { return data_[i]; }
  const T& operator[](size_t i) const { return data_[i]; }

 private:
  void swap(HugePageBuffer& o) noexcept {
    std::swap(data_, o.data_);
    std::swap(size_, o.size_);
  }
  T* data_ = nullptr;
  size_t size_ = 0;
};

}  // namespace raylab
