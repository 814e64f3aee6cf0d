#pragma once
// The start every grid builder shares: the triangles copied for the leaves
// (in id order), the mesh bounds, the padded grid box and the memory budget.
#include <cstdint>
#include <vector>

#include "accel/core/leaf_triangle.h"
#include "accel/grid/dda_grid.h"
#include "accel/grid/grid_options.h"
#include "accel/grid/grid_resolution.h"

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
};

// Fills `tris` and `empty`; returns false for an empty mesh (nothing to build).
inline bool start_grid_build(const TriangleMesh& mesh, const GridOptions& opt, std::vector<LeafTriangle>& tris,
                             bool& empty, GridBuildStart& s) {
  s.triangles = mesh.num_triangles();
  tris = copy_leaf_triangles(mesh);
  empty = s.triangles == 0;
  if (empty) return false;
  s.bounds = mesh.bounds();
  padded_grid_box(s.bounds, s.lo, s.hi);
  s.extent = (s.bounds.hi - s.bounds.lo).cast<double>();
  s.budget = opt.budget_bytes();
  return true;
}

}  // namespace raylab
