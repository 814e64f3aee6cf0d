#pragma once
// The generic batch shell: the batch loops of the Accelerator interface
// around a structure's templated single-ray kernel
//   template <TriangleTest kTest, bool kAnyHit, bool kCount>
//   Hit trace(const Ray& ray, TraversalStats* stats) const;
// Dispatch is virtual per batch (and on the triangle test, once per batch);
// the loop inside calls the kernel directly. `Base` is the interface the
// shell implements: Accelerator, or a structure's own per-layout interface
// with the same two batch calls.
#include "accel/accelerator.h"
#include "accel/core/intersect_triangle.h"

namespace raylab {

template <typename Structure, typename Base = Accelerator>
class BatchAccelerator : public Base {
 protected:
  explicit BatchAccelerator(TriangleTest test) : test_(test) {}

 public:
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, TraversalStats* stats) const override {
    const Structure& s = static_cast<const Structure&>(*this);
    dispatch_triangle_test(test_, [&]<TriangleTest kTest>() {
      if (stats) {
        for (size_t i = 0; i < rays.size(); ++i) hits[i] = s.template trace<kTest, false, true>(rays[i], stats);
      } else {
        for (size_t i = 0; i < rays.size(); ++i) hits[i] = s.template trace<kTest, false, false>(rays[i], nullptr);
      }
    });
  }

  void occluded(std::span<const Ray> rays, std::span<uint8_t> occ, TraversalStats* stats) const override {
    const Structure& s = static_cast<const Structure&>(*this);
    dispatch_triangle_test(test_, [&]<TriangleTest kTest>() {
      if (stats) {
        for (size_t i = 0; i < rays.size(); ++i) occ[i] = s.template trace<kTest, true, true>(rays[i], stats).valid();
      } else {
        for (size_t i = 0; i < rays.size(); ++i) occ[i] = s.template trace<kTest, true, false>(rays[i], nullptr).valid();
      }
    });
  }

  TriangleTest triangle_test() const { return test_; }

 private:
  TriangleTest test_;
};

}  // namespace raylab
