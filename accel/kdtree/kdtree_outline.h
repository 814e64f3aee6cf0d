#pragma once
// Structure picture of a k-d tree (Accelerator::outline): the root cell as a
// box, then every inner node's split plane clipped to its cell (a quad of
// the node's depth), and the cells of leaves at or above max_depth as boxes
// (non-empty leaves only; empty ones are the space the tree cut away).
#include <span>

#include "accel/kdtree/kdtree_node.h"
#include "accel/structure_outline.h"

namespace raylab {

void outline_kdtree(const Aabb& bounds, std::span<const KdNode> nodes, int max_depth, StructureOutline& out);

}  // namespace raylab
