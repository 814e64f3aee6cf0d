#pragma once
// Linear BVH for build speed: centroids sorted along a 63-bit Morton curve
// (21 bits per axis, Lauterbach et al. 2009), internal nodes found
// independently per node from the longest common prefixes of neighbouring
// codes (Karras, "Maximizing Parallelism in the Construction of BVHs, Octrees,
// and k-d Trees", HPG 2012), boxes fitted bottom-up with atomic counters.
// Equal codes (coincident centroids) are ordered by index and split by the
// index's prefix, as Karras prescribes, so they still form a balanced subtree.
// Leaves hold one primitive; leaves are formed later by the SAH-optimal collapse.
#include <span>

#include "accel/bvh/build_common.h"

namespace raylab {

BinaryBvh build_lbvh(std::span<const Aabb> boxes, std::span<const Vec3f> centroids);

// Spreads the low 21 bits of v so that bit i lands on bit 3i.
uint64_t morton_spread21(uint32_t v);

}  // namespace raylab
