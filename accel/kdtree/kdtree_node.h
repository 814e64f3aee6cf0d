#pragma once
// k-d tree layout: compact 8-byte nodes in one flat array, and one flat array
// of triangle ids for the leaves.
//
// Inner node: the split position (float) and, packed in the second word, the
// split axis (low 2 bits) and the index of the child pair (upper 30 bits):
// the child below the plane is at `child`, the one above at `child + 1`, so a
// pair shares 16 bytes and a cache line holds four pairs.
// Leaf: the first word is the offset of its triangles in the leaf array, the
// second word has 3 in the low 2 bits and the triangle count above them.
// (Havran's thesis, 2000, and pbrt use the same 8-byte idea with a
// depth-first "below child follows its parent" order; the pair order lets the
// parallel builder allocate both children at once.)
#include <bit>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "base/aabb.h"

namespace raylab {

// Hard limit of the tree depth (root = depth 0). The traversal stack holds one
// entry per level, so it never overflows.
inline constexpr int kKdMaxDepthLimit = 64;
// 30 bits of child index / leaf count.
inline constexpr uint32_t kKdMaxIndex = (1u << 30) - 1;

struct KdNode {
  uint32_t word0 = 0;  // inner: split position bits; leaf: first entry in the leaf array
  uint32_t word1 = 3;  // low 2 bits: axis 0..2, or 3 = leaf; upper 30: child pair or count

  static KdNode inner(int axis, float split, uint32_t child_pair) {
    KdNode n;
    n.word0 = std::bit_cast<uint32_t>(split);
    n.word1 = (child_pair << 2) | static_cast<uint32_t>(axis);
    return n;
  }
  static KdNode leaf(uint32_t offset, uint32_t count) {
    KdNode n;
    n.word0 = offset;
    n.word1 = (count << 2) | 3u;
    return n;
  }

  bool is_leaf() const { return (word1 & 3u) == 3u; }
  int axis() const { return static_cast<int>(word1 & 3u); }
  float split() const { return std::bit_cast<float>(word0); }
  uint32_t child() const { return word1 >> 2; }  // below child; above child is child() + 1
  uint32_t offset() const { return word0; }
  uint32_t count() const { return word1 >> 2; }
};
static_assert(sizeof(KdNode) == 8, "KdNode must stay 8 bytes");

// The canonical tree every k-d builder produces (node 0 is the root).
struct KdTree {
  Aabb bounds;                     // root cell = bounds of the mesh
  std::vector<KdNode> nodes;
  std::vector<uint32_t> prim_ids;  // leaf ranges [offset, offset + count)
};

// Default depth limit of Havran's thesis / pbrt: 8 + 1.3 log2 N, capped by the
// stack size.
inline int kd_default_max_depth(size_t num_triangles) {
  const double d = 8.0 + 1.3 * std::log2(static_cast<double>(std::max<size_t>(num_triangles, 1)));
  return std::min(kKdMaxDepthLimit, static_cast<int>(std::lround(d)));
}

// Figures of a finished tree. Costs use C_t = C_i = 1 and are normalised by
// the root cell's area, like the BVH's, so the two are comparable.
struct KdTreeShape {
  size_t nodes = 0, inner = 0, leaves = 0, empty_leaves = 0;
  size_t references = 0;    // sum of leaf sizes
  size_t max_leaf_size = 0;
  int max_depth = 0;
  double avg_leaf_depth = 0.0;
  double sah_cost = 0.0;
};

KdTreeShape measure_kdtree(const Aabb& bounds, std::span<const KdNode> nodes);

}  // namespace raylab
