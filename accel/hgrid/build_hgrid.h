#pragma once
// Hierarchical grid construction (hgrid.h): the finest cell side r_0 is the
// smallest triangle extent (at least 2^-18 of the scene's largest side, so a
// level has at most ~2^18 cells per axis), each triangle goes to the level
// l = the smallest with r_0 ratio^l >= its largest extent; its cells are
// collected as (key, triangle) pairs, sorted (parallel), and the runs become
// the cell lists of the shared hash table. O(N log N) for the sort.
#include "accel/accelerator.h"
#include "accel/hgrid/hgrid.h"

namespace raylab {

struct HgridOptions {
  double ratio = 2.0;
  HgridNeighbours neighbours = HgridNeighbours::Store;
};

Hgrid build_hgrid(const TriangleMesh& mesh, const HgridOptions& opt, BuildStats& stats);

}  // namespace raylab
