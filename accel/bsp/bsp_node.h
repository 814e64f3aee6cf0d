#pragma once
// The BSP builder's output (repacked into 8-byte nodes for tracing,
// bsp_packed_node.h): 24-byte nodes in one flat array, children in pairs (the
// child below the plane at `child`, the one above at `child + 1`), leaves
// referring to ranges of an index array, as in the k-d tree
// (accel/kdtree/kdtree_node.h) of which this is the generalisation.
//
// Kinds: 0..2 an axis-aligned plane x_k = d (the k-d fast path), 3 a general
// plane n . x = d with a unit normal n, 4 a leaf, 5 a plane on one of the
// fixed 26-DOP diagonals (n as for 3, its index in bsp_fixed_directions() in
// the bits above the kind, so traversal can use per-ray constants for it).
// "Below" is n . x < d.
#include <cstdint>
#include <vector>

#include "base/aabb.h"

namespace raylab {

inline constexpr uint32_t kBspGeneral = 3;
inline constexpr uint32_t kBspLeaf = 4;
inline constexpr uint32_t kBspFixed = 5;
inline constexpr int kBspMaxDepthLimit = 64;

struct BspNode {
  float n[3] = {0, 0, 0};
  float d = 0;
  uint32_t index = 0;  // inner: below child (above = index + 1); leaf: first entry in the index array
  uint32_t bits = kBspLeaf;  // low 3 bits: kind; leaves: triangle count above them

  uint32_t kind() const { return bits & 7u; }
  bool is_leaf() const { return kind() == kBspLeaf; }
  uint32_t count() const { return bits >> 3; }
  uint32_t direction() const { return bits >> 3; }  // kBspFixed: index of the fixed direction

  static BspNode leaf(uint32_t offset, uint32_t count) {
    BspNode b;
    b.index = offset;
    b.bits = (count << 3) | kBspLeaf;
    return b;
  }
  static BspNode inner(uint32_t kind, const float normal[3], float d, uint32_t child_pair, uint32_t direction = 0) {
    BspNode b;
    for (int a = 0; a < 3; ++a) b.n[a] = normal[a];
    b.d = d;
    b.index = child_pair;
    b.bits = kind | (direction << 3);
    return b;
  }
};
static_assert(sizeof(BspNode) == 24);

struct BspTree {
  Aabb bounds;
  std::vector<BspNode> nodes;      // node 0 = root
  std::vector<uint32_t> prim_ids;  // leaf ranges
};

}  // namespace raylab
