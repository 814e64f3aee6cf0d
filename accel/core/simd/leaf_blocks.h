#pragma once
// A leaf's triangles as SIMD triangle blocks (triangle_block.h): the one
// filler of every structure whose leaves hold blocks (the k-d tree and the
// BSP tree, the grids' cells, the irregular grid's cells, the octrees' nodes,
// the wide BVH's leaves). A leaf of n triangle ids becomes
// triangle_blocks<W>(n) consecutive blocks holding the triangles W at a time
// in the order of the ids; the last block's missing lanes repeat its first
// triangle (fill_block).
#include <algorithm>
#include <cstdint>

#include "accel/core/simd/triangle_block.h"
#include "base/triangle_mesh.h"

namespace raylab {

// What a block stores per triangle: its three corners (the watertight test,
// intersect_block with a BlockRay) or its first corner and two edges
// (tri=mt: the Moller-Trumbore test, intersect_block with a BlockRayMT).
enum class BlockVertices { Corners, Edges };

// Writes the triangle_blocks<W>(count) blocks of the leaf holding
// ids[0..count) to out[0..).
template <int W>
inline void fill_leaf_blocks(const TriangleMesh& mesh, const uint32_t* ids, uint32_t count, TriangleBlock<W>* out,
                             BlockVertices stored = BlockVertices::Corners) {
  const auto vertex = [&](uint32_t prim, int corner) -> const Vec3f& { return mesh.vertex(prim, corner); };
  for (uint32_t i = 0; i < count; i += W, ++out) {
    const int lanes = static_cast<int>(std::min<uint32_t>(count - i, W));
    if (stored == BlockVertices::Edges) fill_block_mt<W>(*out, ids + i, lanes, vertex);
    else fill_block<W>(*out, ids + i, lanes, vertex);
  }
}

// Appends the blocks of the leaf holding ids[0..count) to `blocks` (a vector
// of TriangleBlock<W>) and returns the index of its first block.
template <int W, typename Blocks>
inline uint32_t append_leaf_blocks(const TriangleMesh& mesh, const uint32_t* ids, uint32_t count, Blocks& blocks) {
  const auto first = static_cast<uint32_t>(blocks.size());
  blocks.resize(blocks.size() + triangle_blocks<W>(count));
  fill_leaf_blocks<W>(mesh, ids, count, blocks.data() + first);
  return first;
}

}  // namespace raylab
