#pragma once
// The canonical octree every octree layout is made from, and its pointer
// layout: one flat array of 12-byte nodes in which the eight children of an
// inner node form one contiguous block, found from a single index (no
// per-child pointers). Empty children are real nodes of the block (leaves
// with no triangles) but a mask of non-empty children in the parent lets the
// walk skip them without touching them.
//
// Every node may hold triangles: leaves always, inner nodes only with
// assign=straddle (the textbook scheme: a triangle that straddles a dividing
// plane stays at the inner node, Ericson, Real-Time Collision Detection,
// 7.3). A node's triangles are the index range [first_ref, first_ref +
// count) of one reference array.
#include <cstdint>
#include <vector>

#include "accel/octree/octree_cube.h"

namespace raylab {

// Largest triangle list one node can hold (24 bits of `meta`).
inline constexpr uint32_t kOctMaxNodeRefs = (1u << 24) - 1;

struct OctreeNode {
  uint32_t first_child = 0;  // index of the 8-child block; meaningless when mask() == 0
  uint32_t first_ref = 0;
  uint32_t meta = 0;  // triangle count << 8 | mask of children with triangles in their subtree

  uint32_t count() const { return meta >> 8; }
  uint32_t mask() const { return meta & 0xffu; }
  static uint32_t make_meta(uint32_t count, uint32_t mask) { return count << 8 | mask; }
};
static_assert(sizeof(OctreeNode) == 12);

// Child c of a node: bit k of c set = the upper half along axis k.
struct OctreeTree {
  OctreeCube cube;
  int depth_limit = 0;           // the max_depth in force
  std::vector<OctreeNode> nodes;  // node 0 is the root; children in 8-blocks
  std::vector<uint32_t> refs;     // triangle ids of every node's range
};

// Shape figures of a built tree (all three layouts share them).
struct OctreeShape {
  size_t nodes = 0, inner = 0, leaves = 0, empty_leaves = 0;
  size_t references = 0, inner_references = 0, max_leaf_size = 0;
  size_t nonempty_nodes = 0;  // nodes with triangles in their subtree (the hashed layout's entries)
  std::vector<size_t> nodes_per_level;
  int max_depth = 0;
  double avg_leaf_depth = 0.0, sah_cost = 0.0;
};

OctreeShape measure_octree(const OctreeTree& tree);

}  // namespace raylab
