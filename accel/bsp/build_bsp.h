#pragma once
// SAH builder of the general BSP tree, after Ize, Wald & Parker, "Ray
// Tracing with the BSP Tree", IEEE Symposium on Interactive Ray Tracing 2008.
//
// Candidate planes at a node:
//  - a fixed set of directions (the 3 axes, then the 4 body diagonals and
//    the 6 face diagonals of the 26-DOP: `directions` = 3, 7 or 13), each at
//    `bins` - 1 positions spread over the node's extent along it (binned
//    counts, as in binned BVH builders: O(N) per direction);
//  - the planes of up to `triangle_planes` of the node's triangles (evenly
//    spaced in the node's list), counted exactly. These are what let a BSP
//    leaf hug slanted geometry, the paper's point.
// Each candidate is priced by the SAH with the exact surface areas of the two
// child polytopes (convex_polytope.h), not of boxes; the cheapest wins if it
// beats making a leaf. Every triangle reference carries the part of its
// triangle inside the node's region (clipped by the planes above it, the BSP
// form of the k-d tree's perfect splits), so counts and assignments see only
// what really lies in the region: a reference goes below when its part
// reaches below the plane or lies in it, above when it reaches above, both
// (each with its clipped part) when it straddles. Side tests are done in
// double precision on the stored (float) plane with a tolerance of 1e-12 of
// the scene's magnitude; the traversal's margins are orders of magnitude
// wider, so a triangle that meets a leaf's region is always found there.
//
// Cost: O(N (directions + triangle_planes)) per level plus a constant number
// of polytope clips per node, so O(N log N) for a balanced tree; the depth is
// capped like the k-d tree's (8 + 1.3 log2 N, at most 64).
#include <cstddef>

#include "accel/bsp/bsp_node.h"
#include "base/triangle_mesh.h"

namespace raylab {

struct BspBuildOptions {
  int directions = 13;       // fixed plane directions: 3 (axes), 7 (+ body diagonals), 13 (+ face diagonals)
  int triangle_planes = 8;   // triangle planes tried per node (0 = fixed directions only)
  int bins = 8;              // positions per fixed direction
  float traversal_cost = 15.0f;   // K_T
  float intersection_cost = 20.0f;  // K_I
  float empty_bonus = 0.2f;  // cost reduction of splits with an empty child
  int max_depth = -1;        // negative: 8 + 1.3 log2 N
};

struct BspBuildStats {
  size_t axis_nodes = 0, kdop_nodes = 0, triangle_plane_nodes = 0;
  size_t leaves = 0, empty_leaves = 0, references = 0, max_leaf = 0;
  int max_depth = 0;
  double leaf_depth_sum = 0.0;
  double sah_cost = 0.0;  // reporting constants (accel/core/sah_report.h), polytope areas
  int depth_limit = 0;
};

BspTree build_bsp(const TriangleMesh& mesh, const BspBuildOptions& options, BspBuildStats* stats = nullptr);

// The fixed directions (unit vectors, float as stored in nodes).
const Vec3f* bsp_fixed_directions();

}  // namespace raylab
