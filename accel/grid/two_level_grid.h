#pragma once
// `grid2`: two-level grid. A coarse uniform top grid (density `top`, far
// below one cell per triangle) whose every non-empty cell holds its own
// uniform sub-grid, sized by the n^(1/3) rule for the triangles of that cell
// (density `density`). Jevans & Wyvill, "Adaptive voxel subdivision for ray
// tracing", Graphics Interface 1989; Kalojanov, Stich & Slusallek, "Two-Level
// Grids for Ray Tracing on GPUs", Eurographics 2011.
//
// Two departures from covering each top cell with its sub-grid, both for
// the "teapot in a stadium" (a detailed object in one corner of a top cell
// it shares with big walls or floor):
//  - a sub-grid covers only the part of its top cell that holds triangles
//    (their bounds clipped to the cell), so the object gets all of the
//    sub-grid's cells instead of the few a cell-filling sub-grid leaves it;
//  - "large" triangles, whose part within the cell spans at least half of
//    the cell along two axes (a sheet of floor or wall across it), are kept
//    in a short list of the top cell, tested whenever a ray visits that
//    cell, instead of stretching the sub-grid's box over the whole cell
//    (they would sit in most of its cells anyway).
//
// Layout: top cells map to the record of their contents (or none); every
// sub-grid's cell offsets are stored one after another in one array, into
// one array of triangle ids (compressed-row form, as in the dense grid),
// which also holds the large-triangle lists.
#include <cstdint>
#include <vector>

#include "accel/accelerator.h"
#include "accel/core/grid/dda_grid.h"
#include "accel/grid/grid_options.h"
#include "accel/core/leaf_triangle.h"
#include "accel/core/huge_page_allocator.h"
#include "accel/grid/cell_blocks.h"

namespace raylab {

inline constexpr uint32_t kEmptyTopCell = 0xFFFFFFFFu;

// The contents of one non-empty top cell, 72 bytes: its large triangles and
// a sub-grid over the others. The sub-grid's derived DDA figures (far
// corner, reciprocals, strides) are recomputed when a ray enters it.
struct TopCellContent {
  double lo[3];
  double cell[3];
  int32_t res[3];         // all 0 when the cell has no small triangles (no sub-grid)
  uint32_t offsets_base;  // sub-grid cell c has refs offsets[base + c] .. offsets[base + c + 1]
  uint32_t large_begin;   // large triangles: refs[large_begin .. large_begin + large_count)
  uint32_t large_count;

  bool has_subgrid() const { return res[0] != 0; }
  DdaGrid dda() const { return make_dda_grid_from_cells(lo, cell, res); }
};
static_assert(sizeof(TopCellContent) == 72);

struct TwoLevelGrid {
  DdaGrid top;
  std::vector<uint32_t> top_cells;  // per top cell: index into contents, or kEmptyTopCell
  std::vector<TopCellContent> contents;
  std::vector<uint32_t> offsets;
  std::vector<uint32_t> refs;
  std::vector<LeafTriangle> tris;
  // With SIMD blocks (options.leaf_blocks()) offsets, large_begin and
  // large_count count blocks, and refs and tris are empty.
  HugePageVector<CellTriangleBlock> blocks;  // on huge pages (huge_page_allocator.h)
  bool empty = true;
};

// Builds within the options' memory budget (lowering densities with one
// warning when needed). Fills `stats` except build_ms.
TwoLevelGrid build_two_level_grid(const TriangleMesh& mesh, const GridOptions& options, BuildStats& stats);

}  // namespace raylab
