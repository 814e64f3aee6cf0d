#pragma once
// SAH builder of the general BSP tree, after Ize, Wald & Parker, "Ray
// Tracing with the BSP Tree", IEEE Symposium on Interactive Ray Tracing 2008.
//
// Candidate planes at a node:
//  - a fixed set of directions (the 3 axes, then the 4 body diagonals and
//    the 6 face diagonals of the 26-DOP: `directions` = 3, 7 or 13). Along
//    each, every reference's extent is projected once per node and the
//    sorted start / end / planar events are swept exactly as in the k-d
//    tree's SAH builder (Wald & Havran 2006), so every position where a
//    count changes is a candidate (`bins` >= 2: bins - 1 binned positions
//    instead, the original scheme, kept for the sweep); the diagonals only
//    in regions already cut by a slanted plane unless `diagonals_in_boxes`
//    (in box regions their greedy wins cost more further down: see
//    find_split);
//  - the planes of up to `triangle_planes` of the node's triangles (evenly
//    spaced in the node's list), counted exactly. These are what let a BSP
//    leaf hug slanted geometry, the paper's point.
// Pricing: while every plane above a node is axis-aligned its region is a
// box and axis candidates get the k-d tree's closed-form areas (exact). All
// other candidates are first priced with the box of the region in the
// plane's own frame, and the few cheapest of those are re-priced with the
// exact surface areas of the two child polytopes (convex_polytope.h), as
// Ize et al. do; the cheapest exactly priced plane wins if it beats making a
// leaf (Wald & Havran's termination: SAH cost < K_I N). The empty-space
// bonus is given to axis planes only (on slanted planes it shaved empty
// corners off box-like rooms level after level). With `directions` =
// 3 and no triangle planes this is the k-d tree's builder (same costs, empty
// bonus, sides of lying references, flat cells, perfect splits by clipping,
// depth limit and straddling guard).
//
// Every triangle reference carries the part of its triangle inside the
// node's region (clipped by the planes above it, the BSP form of the k-d
// tree's perfect splits), so counts and assignments see only what really
// lies in the region: a reference goes below when its part reaches below
// the plane, above when it reaches above, both (each with its clipped part)
// when it straddles; one lying in the plane goes to the side the SAH priced
// cheaper (both are priced, as in the k-d tree: a floor's triangles belong
// with the room above it), and a plane on a box region's boundary may cut
// off a flat cell holding the references lying in it (the k-d tree's rule). Event positions are rounded outward to
// float (the stored plane's precision), so a plane at an event has the
// reference on the side it was counted on. Side tests are done in double
// precision on the stored (float) plane with a tolerance of 1e-12 of the
// scene's magnitude; the traversal's margins are orders of magnitude wider,
// so a triangle that meets a leaf's region is always found there.
//
// Cost: the events along each fixed direction are sorted once, at the root,
// and split in order between the children (Wald & Havran's presorted event
// lists, generalised from 3 axes to the swept directions); only the parts of
// straddling references get new events, sorted and merged in. A node of n
// references then costs O(n (directions + triangle_planes)) plus
// O(s log s) for its s straddling references and a constant number of
// polytope clips, so O(N log N) for a balanced tree (measured in
// docs/structures/bsp.md); the depth is capped like the k-d tree's
// (8 + 1.3 log2 N, at most 64).
#include <cstddef>

#include "accel/bsp/bsp_node.h"
#include "base/triangle_mesh.h"

namespace raylab {

struct BspBuildOptions {
  int directions = 13;       // fixed plane directions: 3 (axes), 7 (+ body diagonals), 13 (+ face diagonals)
  int triangle_planes = 8;   // triangle planes tried per node (0 = fixed directions only)
  // Whether the 26-DOP diagonals are candidates in box regions too (true), or
  // only in regions already cut by a slanted plane (false, the default; see
  // find_split in build_bsp.cpp and docs/structures/bsp.md for why).
  bool diagonals_in_boxes = false;
  int bins = 0;              // 0: exact event sweep; 2..64: bins - 1 binned positions per direction
  float traversal_cost = 15.0f;   // K_T
  float intersection_cost = 20.0f;  // K_I
  float empty_bonus = 0.2f;  // cost reduction of axis splits with an empty child
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
