#include "accel/grid/uniform_grid.h"

#include <numeric>
#include <stdexcept>

#include <fmt/format.h>

#include "accel/grid/grid_build_start.h"
#include "accel/grid/grid_stats.h"

namespace raylab {

UniformGrid build_uniform_grid(const TriangleMesh& mesh, const GridOptions& opt, BuildStats& stats) {
  UniformGrid g;
  GridBuildStart start;
  if (!start_grid_build(mesh, opt, g, start)) return g;
  // Cells (one 4-byte offset each) may take half of the budget; the
  // references must fit in what the offsets leave.
  const uint64_t budget = start.budget;
  const uint64_t max_cells = std::max<uint64_t>(1, budget / 2 / sizeof(uint32_t) - 1);
  ChosenResolution chosen = start.first_resolution(opt, max_cells);

  std::vector<uint32_t> ids(start.triangles);
  std::iota(ids.begin(), ids.end(), 0u);
  while (true) {
    g.dda = make_dda_grid(start.lo, start.hi, chosen.res);
    const uint64_t offset_bytes = (g.dda.cells() + 1) * sizeof(uint32_t);
    const uint64_t max_refs = budget > offset_bytes ? (budget - offset_bytes) / sizeof(uint32_t) : 0;
    if (build_cell_lists(g.dda, opt.assign, g.tris, ids, max_refs, g.lists)) break;
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
  stats.bytes = g.lists.bytes() + g.tris.capacity() * sizeof(LeafTriangle) + sizeof(UniformGrid);
  return g;
}

}  // namespace raylab
