#pragma once
// The traversal structure behind `bvh`: the tree in its layout and its walks,
// one virtual call per batch. The wide layouts' kernels are compiled one node
// width per translation unit (wide_kernel_4.cpp, _8, _16), so a build spreads
// them over cores.
#include <cstddef>
#include <memory>
#include <span>

#include "accel/accelerator.h"
#include "accel/bvh/bvh_config.h"
#include "accel/bvh/collapse_wide.h"

namespace raylab {

class BvhKernel {
 public:
  virtual ~BvhKernel() = default;
  virtual void intersect(std::span<const Ray> rays, std::span<Hit> hits, TraversalStats* stats) const = 0;
  virtual void occluded(std::span<const Ray> rays, std::span<uint8_t> occ, TraversalStats* stats) const = 0;
  virtual void outline(int max_depth, StructureOutline& out) const = 0;
};

// The N-wide kernel (N = 4, 8 or 16) for the collapsed tree, as the config
// asks: vector or scalar tests (simd), packets, the triangle test. Sets
// `bytes` to the memory the layout holds.
template <int N>
std::unique_ptr<BvhKernel> make_wide_kernel(const WideTree& tree, const TriangleMesh& mesh, const BvhConfig& cfg,
                                            size_t& bytes);

}  // namespace raylab
