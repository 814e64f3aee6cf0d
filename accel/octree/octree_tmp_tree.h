#pragma once
// The pointer tree both octree builders grow (accel/octree/build_octree.cpp
// and accel/loose_octree/build_loose_octree.cpp) before it is written into
// the flat 8-child-block layout of octree_node.h.
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "accel/octree/octree_node.h"

namespace raylab {

struct OctTmpNode {
  std::vector<uint32_t> refs;  // triangles held by this node (leaves; inner nodes with straddle / loose lists)
  std::unique_ptr<std::array<OctTmpNode, 8>> kids;
  bool nonempty = false;  // triangles anywhere in the subtree
};

// Depth-first into tree.nodes / tree.refs: the eight children of a node are
// allocated together, so one index finds all of them, and a child's block
// follows soon after its parent's (measured on Sponza: breadth-first order
// left the walk waiting on node loads far more often). Throws
// std::length_error (message starting with `what`) when a node holds more
// than kOctMaxNodeRefs triangles or an index would overflow 32 bits.
void flatten_octree(const OctTmpNode& root, OctreeTree& tree, const char* what);

}  // namespace raylab
