#pragma once
// The figures every grid reports, in BuildStats and its `extra` map:
//   nodes = cells, leaves = non-empty cells,
//   extra: empty_fraction, refs_per_triangle, mean_tris_per_nonempty_cell,
//          max_tris_per_cell, res_x/res_y/res_z, lambda, lambda_requested.
#include <cstdint>

#include "accel/accelerator.h"
#include "accel/core/grid/grid_resolution.h"

namespace raylab {

inline void add_occupancy_stats(BuildStats& s, uint64_t cells, uint64_t nonempty, uint64_t refs,
                                uint32_t max_per_cell, size_t triangles) {
  s.nodes = cells;
  s.leaves = nonempty;
  s.extra["cells"] = static_cast<double>(cells);
  s.extra["nonempty_cells"] = static_cast<double>(nonempty);
  s.extra["empty_fraction"] = cells ? 1.0 - static_cast<double>(nonempty) / static_cast<double>(cells) : 0.0;
  s.extra["refs"] = static_cast<double>(refs);
  s.extra["refs_per_triangle"] = triangles ? static_cast<double>(refs) / static_cast<double>(triangles) : 0.0;
  s.extra["mean_tris_per_nonempty_cell"] = nonempty ? static_cast<double>(refs) / static_cast<double>(nonempty) : 0.0;
  s.extra["max_tris_per_cell"] = static_cast<double>(max_per_cell);
}

inline void add_resolution_stats(BuildStats& s, const GridRes& res, double lambda_used, double lambda_requested) {
  s.extra["res_x"] = res[0];
  s.extra["res_y"] = res[1];
  s.extra["res_z"] = res[2];
  s.extra["lambda"] = lambda_used;
  s.extra["lambda_requested"] = lambda_requested;
}

}  // namespace raylab
