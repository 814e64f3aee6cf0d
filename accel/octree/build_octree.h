#pragma once
// Top-down octree construction: the root is the scene's bounding cube
// (octree_cube.h), split into eight equal children until a node holds at
// most `leaf` triangles or the depth limit is reached.
//
// assign=exact: a triangle goes to every child it truly overlaps (the
// separating axis test of Akenine-Moller 2001, accel/grid/tri_box_overlap.h,
// on the children's exact float planes). A triangle whose bounding box lies
// on one side of every dividing plane needs no test: its part inside the
// parent lies in that one child.
// assign=straddle: a triangle whose bounding box straddles a dividing plane
// stays at the inner node (each triangle is stored exactly once).
//
// Cost: every level touches each reference a constant number of times and
// the depth is bounded (O(log N) for well-spread input), so the build is
// O(N log N); subtrees with many references are built in parallel (TBB).
#include <cstdint>

#include "accel/octree/octree_node.h"
#include "base/triangle_mesh.h"

namespace raylab {

enum class OctreeAssign : uint8_t { Exact, Straddle };

struct OctreeBuildOptions {
  uint32_t leaf = 4;      // a node with at most this many triangles becomes a leaf
  int max_depth = 16;     // root = depth 0; at most kOctMaxLevel
  // assign=exact: a split whose children hold more than this many times the
  // node's references is not made (the node stays a leaf).
  double max_growth = 2.0;
  OctreeAssign assign = OctreeAssign::Exact;
  // term=sah: a node above `leaf` is split only when the surface-area cost
  // of its eight children, taken as leaves, beats keeping it as a leaf
  // (MacDonald & Booth 1990's greedy termination; each child cube has 1/4
  // of its parent's surface, so it is met by 1/4 of the rays that meet the
  // parent): ct + sum_c blocks(n_c) / 4 < blocks(n), in units of one
  // 4-wide triangle block test; ct is the cost of visiting a node.
  bool sah = true;
  double ct = 2.0;
};

// Throws std::length_error when a node would hold more than kOctMaxNodeRefs
// triangles or the references would overflow 32-bit indices.
OctreeTree build_octree(const TriangleMesh& mesh, const OctreeBuildOptions& opt);

}  // namespace raylab
