#pragma once
// Baseline k-d tree builder for the study: every cell is split in the middle
// of its longest axis (the classic spatial median, no cost model), until it
// holds at most `median_leaf_size` triangles, reaches the depth limit, or no
// axis makes progress: fewer triangles on at least one side, with less than
// half of them straddling the plane (no reference blow-up). Straddling
// triangles are clipped to the children like the SAH builder's (perfect
// splits, or boxes with clip=0).
#include "base/triangle_mesh.h"
#include "accel/kdtree/kd_build_options.h"
#include "accel/kdtree/kdtree_node.h"

namespace raylab {

KdTree build_kdtree_median(const TriangleMesh& mesh, const KdBuildOptions& options);

}  // namespace raylab
