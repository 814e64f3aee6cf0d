#pragma once
// `grid2`: two-level grid. A coarse uniform top grid (density `top`, far
// below one cell per triangle) whose every non-empty cell holds its own
// uniform sub-grid, sized by the n^(1/3) rule for the triangles of that cell
// (density `density`). Jevans & Wyvill, "Adaptive voxel subdivision for ray
// tracing", Graphics Interface 1989; Kalojanov, Stich & Slusallek, "Two-Level
// Grids for Ray Tracing on GPUs", Eurographics 2011.
//
// A sub-grid does not cover its whole top cell but only the part of it that
// holds triangles: the bounds of the cell's triangles clipped to the cell.
// This is what keeps the structure usable for a "teapot in a stadium": a
// detailed object occupying a small corner of one top cell gets all of its
// sub-grid's cells, instead of the few that a cell-filling sub-grid would
// leave on it.
//
// Layout: top cells map to a sub-grid index (or none); every sub-grid's cell
// offsets are stored one after another in one array, into one array of
// triangle ids (compressed-row form, as in the dense grid).
#include <cstdint>
#include <vector>

#include "accel/accelerator.h"
#include "accel/grid/dda_grid.h"
#include "accel/grid/grid_options.h"
#include "accel/grid/grid_triangles.h"

namespace raylab {

inline constexpr uint32_t kNoSubGrid = 0xFFFFFFFFu;

// 64 bytes per non-empty top cell: the DDA's derived figures (far corner,
// reciprocals, strides) are recomputed when a ray enters the sub-grid.
struct SubGrid {
  double lo[3];
  double cell[3];
  int32_t res[3];
  uint32_t offsets_base;  // this sub-grid's cell c has refs offsets[base + c] .. offsets[base + c + 1]

  DdaGrid dda() const { return make_dda_grid_from_cells(lo, cell, res); }
};
static_assert(sizeof(SubGrid) == 64);

struct TwoLevelGrid {
  DdaGrid top;
  std::vector<uint32_t> top_cells;  // per top cell: index into subgrids, or kNoSubGrid
  std::vector<SubGrid> subgrids;
  std::vector<uint32_t> offsets;
  std::vector<uint32_t> refs;
  std::vector<GridTriangle> tris;
  bool empty = true;
};

// Builds within the options' memory budget (lowering densities with one
// warning when needed). Fills `stats` except build_ms.
TwoLevelGrid build_two_level_grid(const TriangleMesh& mesh, const GridOptions& options, BuildStats& stats);

}  // namespace raylab
