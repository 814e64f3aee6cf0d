#pragma once
// Loose octree construction: every triangle is stored exactly once, at the
// deepest node whose loose box (loose_box.h) contains its bounds, going down
// through the child that holds the centre of its bounds. A node whose
// triangles number at most `leaf` (or at depth `max_depth`) keeps them all.
// The result uses the octree's node layout (accel/octree/octree_node.h),
// inner nodes holding lists; children are allocated in 8-blocks, with a
// mask of the non-empty ones. O(N log N): each level moves every triangle
// at most once.
#include "accel/loose_octree/loose_box.h"
#include "accel/octree/octree_node.h"
#include "base/triangle_mesh.h"

namespace raylab {

struct LooseOctreeOptions {
  double looseness = 2.0;  // k >= 1
  uint32_t leaf = 4;
  int max_depth = 20;
};

OctreeTree build_loose_octree(const TriangleMesh& mesh, const LooseOctreeOptions& opt, LooseBoxes& boxes);

}  // namespace raylab
