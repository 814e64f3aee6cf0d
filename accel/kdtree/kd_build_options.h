#pragma once
// Settings shared by the k-d tree builders (spec: "kdtree:ct=15,ci=20,...").
#include <cstddef>

namespace raylab {

// The registry's default K_T for kdtree and bsp, whose leaves are 4-wide
// SIMD triangle blocks (kdtree_accel.cpp says why; measured in
// docs/structures/kdtree.md). KdBuildOptions keeps the published constant
// for the trees traced with scalar leaves (accel/hybrid).
inline constexpr const char* kKdDefaultTraversalCost = "200";

struct KdBuildOptions {
  // Surface area heuristic constants of Wald & Havran 2006 (their K_T and
  // K_I): cost of one traversal step and of one triangle test.
  float traversal_cost = 15.0f;
  float intersection_cost = 20.0f;
  // A split that leaves one child empty (and not flat) has its cost scaled by
  // (1 - empty_bonus), so empty space is cut off eagerly (their lambda = 0.8).
  float empty_bonus = 0.2f;
  // Perfect splits: clip straddling triangles to the child cells; false uses
  // the triangles' bounding boxes instead.
  bool perfect_splits = true;
  // Maximum depth (root = 0); negative means 8 + 1.3 log2 N.
  int max_depth = -1;
  // Spatial median builder only: cells with at most this many triangles
  // become leaves.
  int median_leaf_size = 2;
};

}  // namespace raylab
