#pragma once
// The grid indexing into one tree (`hybrid:inner=entry`): one k-d tree over
// the whole scene plus a coarse grid whose cells each record the deepest
// tree node whose cell contains the grid cell ("entry node", the idea behind
// neighbour links and entry points for secondary rays: Havran's thesis 2000,
// MacDonald & Booth 1990). A ray whose origin lies in a grid cell (and in the
// recorded node's cell) starts its walk at that node instead of the root.
//
// Why a k-d tree and not a BVH: k-d cells partition space, so every hit
// inside an entry node's cell is found in that node's subtree; BVH boxes
// overlap, and a BVH subtree says nothing about the space it bounds.
#include <cstdint>
#include <vector>

#include "accel/hybrid/top_grid.h"
#include "accel/kdtree/kd_build_options.h"
#include "accel/kdtree/traverse_kdtree.h"

namespace raylab {

struct EntryNode {
  Aabb region;        // the node's cell (exact float split positions)
  uint32_t node = 0;  // 0 = the root
  uint32_t depth = 0;
};

struct EntryGrid {
  TopGrid top;                  // cells only (no lists)
  std::vector<KdNode> nodes;    // the whole-scene tree
  std::vector<uint32_t> ids;    // leaf entries: triangle ids (indices into top.tris)
  std::vector<EntryNode> entry; // per top cell
  KdTreeView root;              // the whole tree, starting at the root
  Aabb bounds;
};

EntryGrid build_entry_grid(const TriangleMesh& mesh, double density, const KdBuildOptions& options);

}  // namespace raylab
