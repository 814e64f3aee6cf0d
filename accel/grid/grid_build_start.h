#pragma once
// The start every grid builder shares: the triangles copied for the leaves
// (in id order), the mesh bounds, the padded grid box and the memory budget.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "accel/core/leaf_triangle.h"
#include "accel/core/grid/dda_grid.h"
#include "accel/grid/grid_options.h"
#include "accel/core/grid/grid_resolution.h"

namespace raylab {

struct GridBuildStart {
  size_t triangles = 0;
  Aabb bounds;
  Vec3d lo, hi;      // the padded grid box
  Vec3d extent;      // of the unpadded bounds, for the resolution rule
  uint64_t budget = 0;

  // The first resolution to try (res=AxBxC capped, or the n^(1/3) rule at
  // the requested density), and the next smaller one after `tried` did not
  // fit the budget.
  ChosenResolution first_resolution(const GridOptions& opt, uint64_t max_cells) const {
    return opt.res ? cap_resolution(*opt.res, max_cells)
                   : choose_resolution(extent, static_cast<double>(triangles), opt.density, max_cells);
  }
  ChosenResolution smaller_resolution(const GridOptions& opt, const ChosenResolution& tried, uint64_t max_cells) const {
    return opt.res ? cap_resolution(tried.res, total_cells(tried.res) / 2)
                   : choose_resolution(extent, static_cast<double>(triangles), tried.lambda / 2, max_cells);
  }

  // `chosen` did not fit the budget: moves it to the next smaller resolution
  // (marked capped), or throws when it is one cell already (`owner: a memory
  // budget of B MiB cannot hold the <what> of N triangles`).
  void shrink(const GridOptions& opt, ChosenResolution& chosen, uint64_t max_cells, const char* owner,
              const char* what) const {
    if (total_cells(chosen.res) == 1)
      throw std::runtime_error(fmt::format("{}: a memory budget of {} MiB cannot hold the {} of {} triangles", owner,
                                           opt.budget_mib, what, triangles));
    const ChosenResolution smaller = smaller_resolution(opt, chosen, max_cells);
    chosen.res = smaller.res;
    chosen.lambda = smaller.lambda;
    chosen.capped = true;
  }

  // Says once on stderr what the budget lowered, when it did.
  void warn_if_capped(const GridOptions& opt, const ChosenResolution& chosen, const char* owner) const {
    if (!chosen.capped) return;
    const std::string requested =
        opt.res ? "res=" + format_grid_resolution(*opt.res) : fmt::format("density={}", opt.density);
    const std::string used = opt.res ? "res=" + format_grid_resolution(chosen.res)
                                     : fmt::format("density={:.4g} (res={})", chosen.lambda,
                                                   format_grid_resolution(chosen.res));
    warn_budget_capped(owner, requested, used, opt.budget_mib);
  }
};

// Fills the grid's triangle copies and `empty` flag; returns false for an
// empty mesh (nothing to build).
template <typename Grid>
bool start_grid_build(const TriangleMesh& mesh, const GridOptions& opt, Grid& g, GridBuildStart& s) {
  s.triangles = mesh.num_triangles();
  g.tris = copy_leaf_triangles(mesh);
  g.empty = s.triangles == 0;
  if (g.empty) return false;
  s.bounds = mesh.bounds();
  padded_grid_box(s.bounds, s.lo, s.hi);
  s.extent = (s.bounds.hi - s.bounds.lo).cast<double>();
  s.budget = opt.budget_bytes();
  return true;
}

}  // namespace raylab
