#pragma once
// Binary BVH layout: compact 32-byte nodes in one flat array. The two children
// of an inner node are stored side by side (left at `index`, right at
// `index + 1`), so a node needs no second child pointer.
#include <cstdint>
#include <span>
#include <vector>

#include "accel/core/huge_page_allocator.h"
#include "accel/core/sah_report.h"
#include "base/aabb.h"

namespace raylab {

struct alignas(32) Bvh2Node {
  float lo[3];
  uint32_t index;  // inner: index of the left child; leaf: first entry in prim_ids
  float hi[3];
  uint32_t count;  // 0 for an inner node; number of primitives for a leaf

  bool is_leaf() const { return count != 0; }
  Aabb bounds() const { return Aabb(Vec3f(lo[0], lo[1], lo[2]), Vec3f(hi[0], hi[1], hi[2])); }
  void set_bounds(const Aabb& b) {
    for (int i = 0; i < 3; ++i) {
      lo[i] = b.lo[i];
      hi[i] = b.hi[i];
    }
  }
};
static_assert(sizeof(Bvh2Node) == 32, "Bvh2Node must stay 32 bytes");

// The canonical binary tree every builder produces: node 0 is the root; leaves
// refer to ranges of prim_ids. Other layouts are converted from it.
struct BinaryBvh {
  // Huge pages: tens of megabytes written once per build (builders, the
  // reinsertion's relayout), where first touches of 4 KiB pages cost about
  // three times as much as of 2 MiB ones (1.2 us a page on the Intel VM).
  // Not zeroed: builders size the array for the worst case (2n - 1 nodes)
  // and write the nodes they use, then shrink it; each writes every node
  // below the final size.
  UninitHugePageVector<Bvh2Node> nodes;
  std::vector<uint32_t> prim_ids;
};

// Tree quality is reported with the constants of accel/core/sah_report.h.

struct Bvh2Shape {
  size_t nodes = 0, leaves = 0;
  int max_depth = 0;
  double avg_leaf_depth = 0.0;
  double sah_cost = 0.0;
};

// Walks the tree once: node/leaf counts, depths and SAH cost.
Bvh2Shape measure_tree(std::span<const Bvh2Node> nodes);

// SAH cost only (same constants), as a parallel sum over the node array:
// every node in the array is part of the tree.
double tree_sah_cost(std::span<const Bvh2Node> nodes);

}  // namespace raylab
