#pragma once
// Structure pictures of the grids (Accelerator::outline). Depth 0 is the
// grid's box; depth 1 the occupied cells (grid, hashgrid) or occupied top
// cells (grid2); depth 2 the occupied cells of grid2's sub-grids (drawn
// within the part of the top cell the sub-grid covers). Empty cells are not
// drawn: the occupied ones show where a ray has work to do.
#include "accel/grid/hash_grid.h"
#include "accel/grid/two_level_grid.h"
#include "accel/grid/uniform_grid.h"
#include "accel/structure_outline.h"

namespace raylab {

void grid_outline(const UniformGrid& grid, int max_depth, StructureOutline& out);
void grid_outline(const HashGrid& grid, int max_depth, StructureOutline& out);
void grid_outline(const TwoLevelGrid& grid, int max_depth, StructureOutline& out);

}  // namespace raylab
