#pragma once
// SIMD node lists of the octree: each node's triangles as structure-of-arrays
// triangle blocks (accel/core/simd/triangle_block.h, filled by
// accel/core/simd/leaf_blocks.h), tested kOctBlockWidth at a time by the
// vector watertight test, as the k-d tree does. The vector test computes
// exactly what the scalar one does, lane by lane, and the recorder's tie rule
// picks the same triangle among equal distances, so `simd=0` (scalar tests of
// the same lists) gives the same hits bit for bit
// (tests/accel/test_registry.cpp, Registry.ScalarVariantGivesIdenticalHits).
//
// Width 4: measured against 8 on Sponza and the stadium (docs/structures/octree.md);
// most octree leaves hold 1-8 triangles, so wider blocks mostly test padding.
#include <cstdint>
#include <vector>

#include "accel/core/simd/leaf_blocks.h"
#include "accel/octree/octree_node.h"
#include "base/triangle_mesh.h"

namespace raylab {

inline constexpr int kOctBlockWidth = 4;
using OctTriangleBlock = TriangleBlock<kOctBlockWidth>;

inline uint32_t oct_node_blocks(uint32_t count) { return triangle_blocks<kOctBlockWidth>(count); }

// Fills the blocks of every node with triangles (leaves, and inner nodes
// with assign=straddle), in node order, and rewrites each such node's
// first_ref to its first block. The layouts made from the tree afterwards
// copy first_ref, so every layout finds the blocks the same way.
inline std::vector<OctTriangleBlock> make_octree_blocks(const TriangleMesh& mesh, OctreeTree& tree) {
  std::vector<OctTriangleBlock> blocks;
  for (OctreeNode& n : tree.nodes) {
    if (n.count() == 0) continue;
    n.first_ref = append_leaf_blocks<kOctBlockWidth>(mesh, tree.refs.data() + n.first_ref, n.count(), blocks);
  }
  return blocks;
}

}  // namespace raylab
