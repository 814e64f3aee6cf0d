#include "accel/grid/uniform_grid.h"

#include <numeric>
#include <stdexcept>

#include <fmt/format.h>

#include "accel/grid/cell_blocks.h"
#include "accel/grid/cell_clearance.h"
#include "accel/grid/grid_build_start.h"
#include "accel/core/grid/grid_stats.h"

namespace raylab {

UniformGrid build_uniform_grid(const TriangleMesh& mesh, const GridOptions& opt, BuildStats& stats) {
  UniformGrid g;
  GridBuildStart start;
  if (!start_grid_build(mesh, opt, g, start)) return g;
  // Cells (one 4-byte offset each) may take half of the budget; the
  // references (ids, or SIMD blocks) must fit in what the offsets leave.
  const uint64_t budget = start.budget;
  const uint64_t max_cells = std::max<uint64_t>(1, budget / 2 / sizeof(uint32_t) - 1);
  ChosenResolution chosen = start.first_resolution(opt, max_cells);

  std::vector<uint32_t> ids(start.triangles);
  std::iota(ids.begin(), ids.end(), 0u);
  while (true) {
    g.dda = make_dda_grid(start.lo, start.hi, chosen.res);
    const uint64_t offset_bytes = (g.dda.cells() + 1) * sizeof(uint32_t);
    const uint64_t max_refs = budget > offset_bytes ? (budget - offset_bytes) / reference_bytes(opt.leaf_blocks()) : 0;
    if (build_cell_lists(g.dda, opt.assign, g.tris, ids, max_refs, g.lists) &&
        (!opt.leaf_blocks() || offset_bytes + blocks_of_runs(g.lists.offsets) * sizeof(CellTriangleBlock) <= budget))
      break;
    // Too many references: halve the cells and try again.
    start.shrink(opt, chosen, max_cells, "grid", "references");
  }
  start.warn_if_capped(opt, chosen, "grid");

  const CellOccupancy occ = measure_occupancy(g.lists.offsets);
  add_occupancy_stats(stats, occ.cells, occ.nonempty, occ.refs, occ.max_per_cell, start.triangles);
  add_resolution_stats(stats, chosen.res, opt.res ? 0.0 : chosen.lambda, opt.res ? 0.0 : opt.density);
  stats.extra["budget_capped"] = chosen.capped ? 1.0 : 0.0;
  stats.max_depth = 1;
  stats.avg_depth = 1.0;
  if (opt.skip) {
    const uint32_t* offsets = g.lists.offsets.data();
    g.clearance = cell_clearance(g.dda, [&](int64_t c) { return offsets[c + 1] != offsets[c]; });
  }
  if (opt.leaf_blocks()) {
    CellBlocks cb = to_cell_blocks(mesh, g.lists.refs, g.lists.offsets);
    for (uint32_t& o : g.lists.offsets) o = cb.block_at[o];
    g.blocks = std::move(cb.blocks);
    std::vector<uint32_t>().swap(g.lists.refs);
    std::vector<LeafTriangle>().swap(g.tris);
  }
  stats.extra["cell_blocks"] = static_cast<double>(g.blocks.size());
  stats.bytes = g.lists.bytes() + g.tris.capacity() * sizeof(LeafTriangle) +
                g.blocks.capacity() * sizeof(CellTriangleBlock) + g.clearance.capacity() + sizeof(UniformGrid);
  return g;
}

}  // namespace raylab
