#pragma once
// Full-sweep SAH builder: at every node each of the n-1 object splits along
// each axis is evaluated exactly (MacDonald & Booth 1990; the sweep over
// centroids sorted once per axis, kept sorted by stable partitioning, as in
// Wald, Boulos & Shirley 2007). O(n log n); the quality reference for the
// binned builder. Parallel with TBB: the three axes sweep as tasks on large
// nodes, subtrees are tasks.
#include <span>

#include "accel/bvh/build_common.h"

namespace raylab {

BinaryBvh build_sweep_sah(std::span<const Aabb> boxes, std::span<const Vec3f> centroids, const BuildOptions& options);

}  // namespace raylab
