#pragma once
// The pointer tree both octree builders grow (accel/octree/build_octree.cpp
// and accel/loose_octree/build_loose_octree.cpp) before it is written into
// the flat 8-child-block layout of octree_node.h.
#include <array>
#include <cstdint>
#include <memory>
#include <numeric>
#include <utility>
#include <vector>

#include "accel/core/triangle_boxes.h"
#include "accel/octree/octree_node.h"
#include "base/triangle_mesh.h"

namespace raylab {

struct OctTmpNode {
  std::vector<uint32_t> refs;  // triangles held by this node (leaves; inner nodes with straddle / loose lists)
  std::unique_ptr<std::array<OctTmpNode, 8>> kids;
  bool nonempty = false;  // triangles anywhere in the subtree
};

// The stopping rule both builders share: a node with at most `leaf`
// triangles, or at the depth limit, keeps `ids` as its list (returns true).
inline bool keep_as_leaf(OctTmpNode& n, std::vector<uint32_t>& ids, int level, uint32_t leaf, int max_depth) {
  if (ids.size() > leaf && level < max_depth) return false;
  n.nonempty = !ids.empty();
  n.refs = std::move(ids);
  return true;
}

// Depth-first into tree.nodes / tree.refs: the eight children of a node are
// allocated together, so one index finds all of them, and a child's block
// follows soon after its parent's (measured on Sponza: breadth-first order
// left the walk waiting on node loads far more often). Throws
// std::length_error (message starting with `what`) when a node holds more
// than kOctMaxNodeRefs triangles or an index would overflow 32 bits.
void flatten_octree(const OctTmpNode& root, OctreeTree& tree, const char* what);

// Throws std::length_error (message starting with `what`) when the mesh has
// more than 2^32 triangles: node lists hold 32-bit indices.
void check_octree_triangle_count(size_t triangles, const char* what);

// The frame both builders share: every triangle's box, one empty leaf for an
// empty mesh, the cube around the bounds, a root holding every triangle,
// grown by `grow(cube, triangle_boxes, root, ids)`, then flattened.
template <typename Grow>
OctreeTree build_octree_tree(const TriangleMesh& mesh, int max_depth, const char* what, Grow&& grow) {
  OctreeTree tree;
  tree.depth_limit = max_depth;
  const size_t n = mesh.num_triangles();
  check_octree_triangle_count(n, what);
  std::vector<Aabb> boxes;
  const Aabb bounds = triangle_boxes(mesh, boxes);
  if (n == 0) {
    tree.nodes.assign(1, OctreeNode{});
    return tree;
  }
  tree.cube = octree_cube_around(bounds);
  std::vector<uint32_t> ids(n);
  std::iota(ids.begin(), ids.end(), 0u);
  OctTmpNode root;
  grow(tree.cube, boxes, root, std::move(ids));
  flatten_octree(root, tree, what);
  return tree;
}

}  // namespace raylab
