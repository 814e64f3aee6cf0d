#pragma once
// SAH k-d tree builder in O(N log N): Wald & Havran, "On building fast
// kd-Trees for Ray Tracing, and on doing that in O(N log N)", IEEE Symposium
// on Interactive Ray Tracing 2006.
//
// Every triangle contributes, per axis, either a start and an end event (the
// extent of its part inside the cell) or one planar event when that extent is
// a single value. The events of the root are sorted once; a node finds its
// best plane with one sweep per axis over its sorted lists, classifies the
// triangles left / right / both from the events of the chosen axis, and
// splits its lists into the children's by a stable partition. Only the
// triangles that straddle the plane get new events (clipped to each child,
// "perfect splits"); those few are sorted and merged in, so every list stays
// sorted without sorting again.
//
// Planar triangles lying in a candidate plane are put on the side that gives
// the lower cost; a cell of zero width ("flat cell") is allowed only when it
// holds such planar triangles, never empty, and gets no empty-space bonus.
//
// Termination: a leaf when no plane is cheaper than testing every triangle
// (C_leaf = K_I N), at the depth limit, or when a split would reduce neither
// side. Candidate planes leaving more than half of the cell's triangles
// straddling are skipped (a guard of this implementation against reference
// blow-up in flat cells of overlapping coplanar triangles).
// Subtrees are built as parallel TBB tasks.
#include "base/triangle_mesh.h"
#include "accel/kdtree/kd_build_options.h"
#include "accel/kdtree/kdtree_node.h"

namespace raylab {

KdTree build_kdtree_sah(const TriangleMesh& mesh, const KdBuildOptions& options);

}  // namespace raylab
