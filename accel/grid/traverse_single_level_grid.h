#pragma once
// The walk of a single-level grid, shared by `grid` and `hashgrid`, which
// differ only in how a cell's triangle list is found (`Cells`); the per-ray
// state and the stopping rule are every grid kernel's
// (accel/core/grid/grid_ray_query.h).
#include <cstdint>

#include "accel/core/grid/dda.h"
#include "accel/core/grid/grid_ray_query.h"
#include "accel/core/leaf_block_dispatch.h"
#include "accel/core/leaf_triangle.h"
#include "accel/grid/cell_blocks.h"

namespace raylab {

// A single-level grid as its walk sees it; `Cells` finds a cell's run of
// references (dense compressed rows, or a hash table of occupied cells):
// ids into `tris`, or with `blocks` (cell_blocks.h) blocks.
template <typename Cells>
struct SingleLevelGridView {
  DdaGrid dda;
  Cells cells;
  const uint32_t* refs = nullptr;
  const LeafTriangle* tris = nullptr;
  const CellTriangleBlock* blocks = nullptr;  // set when the cells are SIMD blocks
  // Per cell, the distance to the nearest occupied cell (cell_clearance.h),
  // when the walk skips empty space.
  const uint8_t* clearance = nullptr;
  bool empty = true;
};

// Closest-hit / any-hit walk of a single-level grid: the cells of the
// 3D-DDA (dda.h), each non-empty cell's triangles tested (mailboxed), the
// stopping rule of grid_ray_query.h; with a clearance per cell, empty cubes are crossed
// in one jump (dda_walk_skipping), and a cell's clearance says whether it
// is empty before its list is looked up.
template <TriangleTest kTest, bool kAnyHit, bool kCount, bool kFarFirst, typename Cells>
inline Hit traverse_grid(const SingleLevelGridView<Cells>& g, const Ray& ray, TraversalStats* stats) {
  return walk_with_leaf_blocks<kTest>(g, [&]<bool kBlocks>() {
    return walk_grid<kTest, kAnyHit, kCount, kBlocks, kFarFirst, kCellBlockWidth>(g.dda, g.empty, ray, stats,
                                                                                  [&](const DdaRay& dr, double t0,
                                                                                      double t1, auto& q) {
      const auto visit = [&](int64_t cell, double, double t_exit) __attribute__((always_inline)) {
        uint32_t begin, count;
        const bool found = g.cells.find(cell, begin, count);
        q.rec.count_cell(found ? count : 0);
        if (!found) return false;
        return q.visit_run(g, begin, count, t_exit);
      };
      if (g.clearance) {
        dda_walk_skipping(g.dda, dr, t0, t1, [&](int64_t cell) { return g.clearance[cell]; },
                          [&](int64_t cell, double t_enter, double t_exit) __attribute__((always_inline)) {
                            if (g.clearance[cell] != 0) {
                              q.rec.count_cell(0);
                              return false;
                            }
                            return visit(cell, t_enter, t_exit);
                          });
      } else {
        dda_walk(g.dda, dr, t0, t1, visit);
      }
    });
  });
}

}  // namespace raylab
