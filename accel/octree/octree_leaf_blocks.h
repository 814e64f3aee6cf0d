#pragma once
// SIMD node lists of the octree: each node's triangles as the BVH's
// structure-of-arrays triangle blocks (accel/bvh/triangle_block.h), tested
// kOctBlockWidth at a time by the vector watertight test, as the k-d tree
// does (accel/kdtree/kd_leaf_blocks.h). The vector test computes exactly
// what the scalar one does, lane by lane, and the recorder's tie rule picks
// the same triangle among equal distances, so `simd=0` (scalar tests of the
// same lists) gives the same hits bit for bit (tests/test_accelerators.cpp,
// Registry.ScalarVariantGivesIdenticalHits).
//
// Width 4: measured against 8 on Sponza and the stadium (docs/structures/octree.md);
// most octree leaves hold 1-8 triangles, so wider blocks mostly test padding.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "accel/core/simd/triangle_block.h"
#include "accel/octree/octree_node.h"
#include "base/triangle_mesh.h"

namespace raylab {

inline constexpr int kOctBlockWidth = 4;
using OctTriangleBlock = TriangleBlock<kOctBlockWidth>;

inline uint32_t oct_node_blocks(uint32_t count) { return (count + kOctBlockWidth - 1) / kOctBlockWidth; }

// Fills the blocks of every node with triangles (leaves, and inner nodes
// with assign=straddle), in node order, and rewrites each such node's
// first_ref to its first block. The layouts made from the tree afterwards
// copy first_ref, so every layout finds the blocks the same way.
inline std::vector<OctTriangleBlock> make_octree_blocks(const TriangleMesh& mesh, OctreeTree& tree) {
  std::vector<OctTriangleBlock> blocks;
  for (OctreeNode& n : tree.nodes) {
    const uint32_t count = n.count();
    if (count == 0) continue;
    const uint32_t begin = static_cast<uint32_t>(blocks.size());
    for (uint32_t i = 0; i < count; i += kOctBlockWidth) {
      blocks.emplace_back();
      fill_block<kOctBlockWidth>(blocks.back(), tree.refs.data() + n.first_ref + i,
                                 static_cast<int>(std::min<uint32_t>(count - i, kOctBlockWidth)),
                                 [&](uint32_t prim, int corner) -> const Vec3f& { return mesh.vertex(prim, corner); });
    }
    n.first_ref = begin;
  }
  return blocks;
}

}  // namespace raylab
