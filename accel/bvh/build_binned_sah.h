#pragma once
// Binned SAH builder (Wald, "On fast Construction of SAH-based Bounding Volume
// Hierarchies", 2007): split candidates are bin boundaries along each axis of
// the centroid bounds; the cheapest by the surface area heuristic wins.
// Works on primitive boxes and centroids only, never on triangles, so it can
// serve any primitive. Parallel with TBB: large nodes bin and partition in
// parallel (partition into a second buffer, ping-pong), subtrees are tasks.
// One split that is not a centroid split: large references may be given a
// child of their own (BuildOptions::big_node, big_root).
#include <span>
#include <vector>

#include "accel/bvh/build_common.h"

namespace raylab {

struct BinnedBuildStats {
  size_t big_splits = 0;  // nodes whose large references became a child of their own (BuildOptions::big_node)
};

BinaryBvh build_binned_sah(std::span<const Aabb> boxes, std::span<const Vec3f> centroids,
                           const BuildOptions& options, BinnedBuildStats* stats = nullptr);

// Same, on prepared references (consumed).
BinaryBvh build_binned_sah(std::vector<BuildRef> refs, const BuildOptions& options,
                           BinnedBuildStats* stats = nullptr);

}  // namespace raylab
