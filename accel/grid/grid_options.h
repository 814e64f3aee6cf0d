#pragma once
// Settings shared by the three grids, parsed from their spec strings:
//   density=1     lambda of the n^(1/3) rule (cells ~ lambda * triangles)
//   res=AxBxC     explicit resolution (grid, hashgrid), overrides density
//   budget=1024   memory budget in MiB; a larger request lowers lambda with
//                 a warning on stderr instead of failing to allocate
//   assign=exact  exact triangle/box overlap (SAT), or bbox
//   tri=watertight triangle test (watertight or mt)
//   simd=1        cells' triangles as 4-wide SIMD blocks (watertight test
//                 only); 0 keeps the scalar kernels (same hits and counts)
//   skip=1        (grid) empty-space skipping by each cell's distance to the
//                 nearest occupied cell
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "accel/core/any_hit_order.h"
#include "accel/core/intersect_triangle.h"
#include "accel/core/grid/cell_overlap.h"
#include "accel/core/grid/grid_resolution.h"
#include "accel/registry.h"
#include "base/spec.h"

namespace raylab {

struct GridOptions {
  double density = 1.0;
  std::optional<GridRes> res;
  double budget_mib = 1024.0;
  AssignMode assign = AssignMode::Exact;
  TriangleTest test = TriangleTest::Watertight;
  double top_density = 1.0 / 16.0;  // two-level grid only
  bool simd = true;
  bool skip = false;  // dense `grid` only: empty-space skipping (cell_clearance.h)
  // grid2 only: sub=cell, each sub-grid covers its whole top cell and all of
  // its triangles (Kalojanov, Billeter & Slusallek 2011); else sub=fit.
  bool whole_cell_subgrids = false;
  // Any-hit walks start at the segment's far end (accel/core/any_hit_order.h).
  AnyHitOrder any_hit_order = AnyHitOrder::Back;

  // Cells stored as SIMD triangle blocks (cell_blocks.h).
  bool leaf_blocks() const { return simd && test == TriangleTest::Watertight; }

  uint64_t budget_bytes() const { return static_cast<uint64_t>(budget_mib * 1024.0 * 1024.0); }
};

// Declared parameters with their valid values; `with_res` adds res=,
// `with_top` adds top= (grid2).
std::vector<ParamInfo> grid_param_infos(bool with_res, bool with_top);

// Reads the parameters (Params checked them; res= is parsed here and throws
// SpecError when malformed).
GridOptions parse_grid_options(const Params& p, bool with_res, bool with_top);

// The registry entries shared by the grids (capabilities, specs to cover,
// statistic keys) for `name`: "grid", "hashgrid" or "grid2".
void complete_grid_info(AcceleratorInfo& info);

// The one warning printed when a budget lowers the requested density.
void warn_budget_capped(const std::string& owner, const std::string& requested, const std::string& used,
                        double budget_mib);

}  // namespace raylab
