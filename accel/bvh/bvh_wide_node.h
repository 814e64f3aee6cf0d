#pragma once
// N-wide BVH layout (N = 4, 8 or 16): each node holds its children's boxes in
// structure-of-arrays order (all children's lo.x, then hi.x, lo.y, ...), so
// one vector load per plane tests every child at once, and one 32-bit
// reference per child. 4-wide nodes take 128 bytes, 8-wide nodes 256 (four
// cache lines, like Embree's uncompressed BVH8 node), 16-wide nodes 448.
//
// Child references:
//   bit 31 = 0: inner child, the index of its node
//   bit 31 = 1: leaf; bits 27..30 = number of triangle blocks (0..15, 0 for an
//               unused slot), bits 0..26 = index of the first block
// Unused slots have an empty box (lo = +inf, hi = -inf) and an empty leaf, so
// even a spurious hit on them does no work.
#include <cstdint>
#include <limits>
#include <vector>

#include "accel/bvh/collapse_wide.h"
#include "accel/core/huge_page_allocator.h"
#include "accel/core/simd/triangle_block.h"
#include "base/triangle_mesh.h"

namespace raylab {

namespace wide_ref {
inline constexpr uint32_t kLeafBit = 0x80000000u;
inline constexpr int kBlockCountShift = 27;
inline constexpr uint32_t kMaxBlocks = 15;
inline constexpr uint32_t kFirstBlockMask = (1u << kBlockCountShift) - 1u;
inline constexpr uint32_t kEmpty = kLeafBit;  // a leaf with no blocks

inline bool is_leaf(uint32_t ref) { return (ref & kLeafBit) != 0; }
inline uint32_t leaf(uint32_t first_block, uint32_t blocks) {
  return kLeafBit | (blocks << kBlockCountShift) | first_block;
}
inline uint32_t leaf_blocks(uint32_t ref) { return (ref >> kBlockCountShift) & 15u; }
inline uint32_t leaf_first(uint32_t ref) { return ref & kFirstBlockMask; }
}  // namespace wide_ref

template <int N>
struct alignas(64) WideNode {
  // bounds[0] = lo.x, [1] = hi.x, [2] = lo.y, [3] = hi.y, [4] = lo.z, [5] = hi.z
  float bounds[6][N];
  uint32_t child[N];

  Aabb child_box(int i) const {
    return Aabb(Vec3f(bounds[0][i], bounds[2][i], bounds[4][i]), Vec3f(bounds[1][i], bounds[3][i], bounds[5][i]));
  }
};

// Nodes plus triangle blocks; the root is wide node 0 unless root_ref is a
// leaf.
template <int N, int W>
struct WideBvh {
  HugePageVector<WideNode<N>> nodes;
  HugePageVector<TriangleBlock<W>> blocks;
  uint32_t root_ref = wide_ref::kEmpty;
  Aabb root_box;

  size_t bytes() const { return nodes.size() * sizeof(WideNode<N>) + blocks.size() * sizeof(TriangleBlock<W>); }
};

// Converts the collapsed tree into nodes and blocks (parallel over leaves).
template <int N, int W>
// edges: blocks hold (p0, p1 - p0, p2 - p0) for the Moller-Trumbore block test
// (tri=mt), else the three vertices.
WideBvh<N, W> make_wide_bvh(const WideTree& tree, const TriangleMesh& mesh, bool edges = false);

}  // namespace raylab
