#pragma once
// The inner level of the grid of trees: one small tree per non-empty top
// cell, over the triangles the cell lists, built by the existing builders
// (accel/bvh/build_binned_sah.h, accel/kdtree/build_sah_events.h) and traced
// by the existing traversals (traverse_bvh2.h, traverse_kdtree.h). All cells'
// nodes and triangles live in a few flat arrays; each cell's view points into
// them (child indices in both node formats are relative to the view's node
// pointer, so a tree can sit anywhere in the shared array).
//
// BVH cells are built over the triangles' boxes clipped to the (enlarged)
// cell: a ray is traced through a cell only over the cell's interval, and a
// hit outside the cell lies in another cell the walk visits, so the clipped
// boxes lose nothing and are much tighter for large triangles.
#include <cstdint>
#include <vector>

#include "accel/bvh/traverse_bvh2.h"
#include "accel/hybrid/top_grid.h"
#include "accel/kdtree/kd_build_options.h"
#include "accel/kdtree/traverse_kdtree.h"

namespace raylab {

inline constexpr uint32_t kNoCellTree = UINT32_MAX;

// Totals over all cell trees, for BuildStats.
struct CellTreeTotals {
  size_t nodes = 0, leaves = 0, references = 0, trees = 0;
  int max_depth = 0;
  double leaf_depth_sum = 0.0;
  size_t bytes = 0;
};

// One tree per non-empty cell; `cell_tree[cell]` is an index into `views`
// or kNoCellTree.
template <typename Node, typename View>
struct CellForest {
  std::vector<Node> nodes;
  std::vector<LeafTriangle> tris;
  std::vector<uint32_t> ids;  // k-d leaves: indices into the cell's triangles (unused by BVHs)
  std::vector<View> views;
  std::vector<uint32_t> cell_tree;
  CellTreeTotals totals;
};

using CellBvhForest = CellForest<Bvh2Node, Bvh2View>;
using CellKdForest = CellForest<KdNode, KdTreeView>;

// `leaf`: largest BVH leaf (the binned SAH builder decides below that).
CellBvhForest build_cell_bvhs(const TopGrid& grid, int leaf);
CellKdForest build_cell_kdtrees(const TopGrid& grid, const KdBuildOptions& options);

}  // namespace raylab
