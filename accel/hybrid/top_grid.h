#pragma once
// The coarse top level of the hybrid structures: a uniform grid over the
// scene's box with about `density` * N cells (the n^(1/3) rule of
// accel/grid/grid_resolution.h with a small lambda), every cell's triangle
// list in compressed rows (exact triangle/cell overlap, cell margin of
// accel/grid/dda_grid.h). The grid of trees builds one small tree per
// non-empty cell from these lists; the entry-point grid uses only the cells.
#include <cstdint>
#include <vector>

#include "accel/core/leaf_triangle.h"
#include "accel/core/grid/cell_lists.h"
#include "accel/core/grid/dda_grid.h"
#include "base/triangle_mesh.h"

namespace raylab {

struct TopGrid {
  DdaGrid dda;
  CellLists lists;                 // empty when built without lists
  std::vector<LeafTriangle> tris;  // every triangle, in id order
  double density = 0.0;            // the lambda used (lowered when the cell cap bit)
  bool empty = true;               // no triangles
};

// Largest number of top cells (the top level is meant to be coarse).
inline constexpr uint64_t kTopGridMaxCells = uint64_t{1} << 22;

// Builds the grid; `with_lists` = false skips the triangle lists.
TopGrid build_top_grid(const TriangleMesh& mesh, double density, bool with_lists);

// The box of cell (x, y, z) enlarged by the assignment margin, rounded
// outward to float.
Aabb top_cell_box(const DdaGrid& g, int32_t x, int32_t y, int32_t z);

}  // namespace raylab
