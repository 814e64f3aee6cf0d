#pragma once
// SIMD leaves of the k-d tree: each leaf's triangles as the BVH's
// structure-of-arrays triangle blocks (accel/bvh/triangle_block.h), tested
// kKdBlockWidth at a time by the same vector watertight test. That test
// computes exactly what the scalar one does, lane by lane, and picks the
// first lane among equal distances, so the blocks give the same hits as the
// scalar leaves (simd=0), bit for bit (tests/test_kdtree.cpp checks).
//
// Width 4: k-d tree leaves are small (SAH leaves average 2-4 triangles with
// the default costs), so a 4-wide block wastes fewer lanes and half the
// memory of an 8-wide one; measured in docs/structures/kdtree.md.
#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "accel/core/huge_page_allocator.h"
#include "accel/core/simd/triangle_block.h"
#include "accel/kdtree/kdtree_node.h"
#include "base/triangle_mesh.h"

namespace raylab {

inline constexpr int kKdBlockWidth = 4;
using KdTriangleBlock = TriangleBlock<kKdBlockWidth>;

inline uint32_t kd_leaf_blocks(uint32_t count) { return triangle_blocks<kKdBlockWidth>(count); }

// Writes the kd_leaf_blocks(count) blocks of one leaf (its `count`
// triangle ids) to out[0..); shared with the grids' cells (accel/grid).
inline void fill_kd_leaf_blocks(const TriangleMesh& mesh, const uint32_t* ids, uint32_t count, KdTriangleBlock* out) {
  for (uint32_t i = 0; i < count; i += kKdBlockWidth)
    fill_block<kKdBlockWidth>(*out++, ids + i, static_cast<int>(std::min<uint32_t>(count - i, kKdBlockWidth)),
                              [&](uint32_t prim, int corner) -> const Vec3f& { return mesh.vertex(prim, corner); });
}

// Appends the blocks of one leaf (its `count` triangle ids) and returns the
// index of its first block; shared with the BSP tree's leaves (accel/bsp).
inline uint32_t append_kd_leaf_blocks(const TriangleMesh& mesh, const uint32_t* ids, uint32_t count,
                                      HugePageVector<KdTriangleBlock>& blocks) {
  const uint32_t begin = static_cast<uint32_t>(blocks.size());
  blocks.resize(blocks.size() + kd_leaf_blocks(count));
  fill_kd_leaf_blocks(mesh, ids, count, blocks.data() + begin);
  return begin;
}

// Fills the blocks of every leaf, in node order (a leaf's blocks follow the
// previous leaf's), and rewrites each leaf's offset to its first block.
inline HugePageVector<KdTriangleBlock> make_kd_leaf_blocks(const TriangleMesh& mesh, std::span<KdNode> nodes,
                                                           std::span<const uint32_t> prim_ids) {
  HugePageVector<KdTriangleBlock> blocks;
  for (KdNode& n : nodes) {
    if (!n.is_leaf()) continue;
    n = KdNode::leaf(append_kd_leaf_blocks(mesh, prim_ids.data() + n.offset(), n.count(), blocks), n.count());
  }
  return blocks;
}

}  // namespace raylab
