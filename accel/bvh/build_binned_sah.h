#pragma once
// Binned SAH builder (Wald, "On fast Construction of SAH-based Bounding Volume
// Hierarchies", 2007): split candidates are bin boundaries along each axis of
// the centroid bounds; the cheapest by the surface area heuristic wins.
// Works on primitive boxes and centroids only, never on triangles, so it can
// serve any primitive. Parallel with TBB: subtrees are built as tasks and
// large nodes bin in parallel.
#include <span>

#include "accel/bvh/bvh2_node.h"

namespace raylab {

struct BinnedSahOptions {
  int bins = 16;       // bins per axis
  int max_leaf = 4;    // leaves never hold more primitives than this
  float traversal_cost = 1.0f;     // C_t used for split decisions
  float intersection_cost = 1.0f;  // C_i used for split decisions
};

BinaryBvh build_binned_sah(std::span<const Aabb> boxes, std::span<const Vec3f> centroids,
                           const BinnedSahOptions& options);

}  // namespace raylab
