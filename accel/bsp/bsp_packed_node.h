#pragma once
// The traced form of the BSP tree: 8-byte nodes like the k-d tree's
// (accel/kdtree/kdtree_node.h), so a child pair shares 16 bytes and a cache
// line holds four pairs, against 24 bytes per node in the builder's output
// (bsp_node.h). The builder's tree is repacked once, node for node (same
// indices, children still in pairs: below at `child`, above at `child + 1`).
//
// Inner node on a fixed direction (an axis or a 26-DOP diagonal): word0 is
// the plane offset d (float bits) and the low 4 bits of word1 the index of
// the direction in bsp_fixed_directions(); the traversal keeps per-ray
// constants for each direction, so axis and diagonal nodes run the same
// three float operations. Inner node on a free plane (a triangle's plane):
// word0 is the index of its plane in a side array of 16-byte planes, which
// only these nodes touch. Leaf: word0 is the leaf's first entry (index array
// or SIMD block), the upper 28 bits of word1 its triangle count.
#include <bit>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <vector>

#include "accel/bsp/bsp_node.h"

namespace raylab {

inline constexpr uint32_t kBspPackedFreePlane = 13;  // below: a fixed direction index
inline constexpr uint32_t kBspPackedLeaf = 15;
inline constexpr uint32_t kBspPackedMaxIndex = (1u << 28) - 1;

struct alignas(16) BspPlane {
  float n[3];  // unit normal as the builder stored it
  float d;     // below: n . x < d
};

struct BspPackedNode {
  uint32_t word0 = 0;
  uint32_t word1 = kBspPackedLeaf;

  uint32_t code() const { return word1 & 15u; }  // direction index, kBspPackedFreePlane or kBspPackedLeaf
  bool is_leaf() const { return code() == kBspPackedLeaf; }
  bool is_free_plane() const { return code() == kBspPackedFreePlane; }
  float offset() const { return std::bit_cast<float>(word0); }  // fixed-direction nodes
  uint32_t plane() const { return word0; }                      // free-plane nodes
  uint32_t child() const { return word1 >> 4; }                 // below child; above = child() + 1
  uint32_t first() const { return word0; }                     // leaves
  uint32_t count() const { return word1 >> 4; }                 // leaves

  static BspPackedNode pack(uint32_t code, uint32_t word0, uint32_t upper) {
    if (upper > kBspPackedMaxIndex) throw std::length_error("bsp: more than 2^28 nodes or triangles in a leaf");
    return BspPackedNode{word0, (upper << 4) | code};
  }
  static BspPackedNode leaf(uint32_t first, uint32_t count) { return pack(kBspPackedLeaf, first, count); }
};
static_assert(sizeof(BspPackedNode) == 8, "BspPackedNode must stay 8 bytes");

struct BspPackedTree {
  std::vector<BspPackedNode> nodes;  // same indices as the builder's nodes
  std::vector<BspPlane> planes;      // free planes, in node order
};

// Repacks the builder's nodes; leaves keep their offsets into prim_ids.
inline BspPackedTree pack_bsp_nodes(std::span<const BspNode> nodes) {
  BspPackedTree out;
  out.nodes.reserve(nodes.size());
  for (const BspNode& n : nodes) {
    if (n.is_leaf()) {
      out.nodes.push_back(BspPackedNode::leaf(n.index, n.count()));
    } else if (n.kind() == kBspGeneral) {
      out.nodes.push_back(BspPackedNode::pack(kBspPackedFreePlane, static_cast<uint32_t>(out.planes.size()), n.index));
      out.planes.push_back(BspPlane{{n.n[0], n.n[1], n.n[2]}, n.d});
    } else {
      const uint32_t direction = n.kind() == kBspFixed ? n.direction() : n.kind();
      out.nodes.push_back(BspPackedNode::pack(direction, std::bit_cast<uint32_t>(n.d), n.index));
    }
  }
  return out;
}

}  // namespace raylab
