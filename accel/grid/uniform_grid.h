#pragma once
// `grid`: a dense uniform grid over the scene's box, resolution by the
// n^(1/3) rule (grid_resolution.h), cells in compressed-row form
// (cell_lists.h), traversed by the 3D-DDA (traverse_uniform_grid.h).
#include <vector>

#include "accel/accelerator.h"
#include "accel/core/grid/cell_lists.h"
#include "accel/core/grid/dda_grid.h"
#include "accel/grid/grid_options.h"
#include "accel/core/leaf_triangle.h"
#include "accel/core/huge_page_allocator.h"
#include "accel/grid/cell_blocks.h"

namespace raylab {

struct UniformGrid {
  DdaGrid dda;
  // With SIMD blocks (options.leaf_blocks()) the offsets count blocks, and
  // refs and tris are empty.
  CellLists lists;
  std::vector<LeafTriangle> tris;
  HugePageVector<CellTriangleBlock> blocks;  // on huge pages (huge_page_allocator.h)
  // With empty-space skipping (skip=1): per cell the distance to the nearest
  // occupied cell (cell_clearance.h).
  std::vector<uint8_t> clearance;
  bool empty = true;  // no triangles: every ray misses
};

// Builds the grid within the options' memory budget (lowering the density,
// with one warning, when needed). Fills `stats` except build_ms.
UniformGrid build_uniform_grid(const TriangleMesh& mesh, const GridOptions& options, BuildStats& stats);

}  // namespace raylab
