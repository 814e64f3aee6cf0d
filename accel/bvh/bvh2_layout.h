#pragma once
// The binary layout (`layout=bvh2`): the canonical tree after SAH-optimal leaf
// formation (collapse_to_wide with width 2), stored as compact 32-byte
// Bvh2Nodes with sibling pairs side by side, and leaf triangles copied in
// leaf order. Traversed by traverse_bvh2.h.
#include <vector>

#include "accel/bvh/collapse_wide.h"
#include "accel/core/huge_page_allocator.h"
#include "accel/bvh/traverse_bvh2.h"
#include "base/triangle_mesh.h"

namespace raylab {

struct Bvh2Layout {
  HugePageVector<Bvh2Node> nodes;
  HugePageVector<LeafTriangle> tris;

  size_t bytes() const { return nodes.size() * sizeof(Bvh2Node) + tris.size() * sizeof(LeafTriangle); }
  Bvh2View view() const { return Bvh2View{nodes.data(), tris.data(), tris.empty()}; }
};

// `tree` must come from collapse_to_wide with width 2.
Bvh2Layout make_bvh2_layout(const WideTree& tree, const TriangleMesh& mesh);

}  // namespace raylab
