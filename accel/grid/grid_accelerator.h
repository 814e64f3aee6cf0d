#pragma once
// Common shell of the grid accelerators: the batch loops of the
// Accelerator interface around a structure's templated single-ray kernel
// `trace<TriangleTest, kAnyHit, kCount>(ray, stats)`. Dispatch is virtual per
// batch; the loop inside calls the kernel directly.
#include "accel/accelerator.h"
#include "accel/core/intersect_triangle.h"

namespace raylab {

template <typename Structure>
class GridAccelerator : public Accelerator {
 protected:
  explicit GridAccelerator(TriangleTest test) : test_(test) {}

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

 private:
  TriangleTest test_;
};

}  // namespace raylab
