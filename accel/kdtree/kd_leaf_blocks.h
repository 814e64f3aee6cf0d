#pragma once
// SIMD leaves of the k-d tree: each leaf's triangles as structure-of-arrays
// triangle blocks (accel/core/simd/triangle_block.h, filled by
// accel/core/simd/leaf_blocks.h), tested kKdBlockWidth at a time by the
// vector watertight test. That test computes exactly what the scalar one
// does, lane by lane, and picks the first lane among equal distances, so the
// blocks give the same hits as the scalar leaves (simd=0), bit for bit
// (tests/accel/kdtree/test_kdtree.cpp checks).
//
// Width 4: k-d tree leaves are small (SAH leaves average 2-4 triangles with
// the default costs), so a 4-wide block wastes fewer lanes and half the
// memory of an 8-wide one; measured in docs/structures/kdtree.md.
#include <cstdint>
#include <span>

#include "accel/core/huge_page_allocator.h"
#include "accel/core/simd/leaf_blocks.h"
#include "accel/kdtree/kdtree_node.h"
#include "base/triangle_mesh.h"

namespace raylab {

inline constexpr int kKdBlockWidth = 4;
using KdTriangleBlock = TriangleBlock<kKdBlockWidth>;

inline uint32_t kd_leaf_blocks(uint32_t count) { return triangle_blocks<kKdBlockWidth>(count); }

// Fills the blocks of every leaf, in node order (a leaf's blocks follow the
// previous leaf's), and rewrites each leaf's offset to its first block.
inline HugePageVector<KdTriangleBlock> make_kd_leaf_blocks(const TriangleMesh& mesh, std::span<KdNode> nodes,
                                                           std::span<const uint32_t> prim_ids) {
  HugePageVector<KdTriangleBlock> blocks;
  for (KdNode& n : nodes) {
    if (!n.is_leaf()) continue;
    n = KdNode::leaf(append_leaf_blocks<kKdBlockWidth>(mesh, prim_ids.data() + n.offset(), n.count(), blocks),
                     n.count());
  }
  return blocks;
}

}  // namespace raylab
