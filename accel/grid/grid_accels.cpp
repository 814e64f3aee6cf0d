// The three grids behind one Accelerator shell: a grid type, its builder,
// its view (grid_view) and its walk (traverse_grid, overloaded per view).
#include "accel/grid/grid_accels.h"

#include <utility>

#include "accel/core/batch_accelerator.h"
#include "accel/grid/grid_outline.h"
#include "accel/grid/traverse_hash_grid.h"
#include "accel/grid/traverse_two_level_grid.h"
#include "accel/grid/traverse_uniform_grid.h"

namespace raylab {

namespace {

template <typename Grid, Grid (*kBuild)(const TriangleMesh&, const GridOptions&, BuildStats&)>
class GridAccel final : public BatchAccelerator<GridAccel<Grid, kBuild>> {
 public:
  explicit GridAccel(const GridOptions& opt) : BatchAccelerator<GridAccel<Grid, kBuild>>(opt.test), opt_(opt) {}

  template <TriangleTest kTest, bool kAnyHit, bool kCount>
  Hit trace(const Ray& ray, TraversalStats* stats) const {
    return traverse_grid<kTest, kAnyHit, kCount>(view_, ray, stats);
  }
  void outline(int max_depth, StructureOutline& out) const override { grid_outline(grid_, max_depth, out); }

 protected:
  BuildStats build_impl(const TriangleMesh& mesh) override {
    BuildStats s;
    grid_ = kBuild(mesh, opt_, s);
    view_ = grid_view(grid_);
    return s;
  }

 private:
  GridOptions opt_;
  Grid grid_;
  decltype(grid_view(std::declval<const Grid&>())) view_;
};

template <typename Grid, Grid (*kBuild)(const TriangleMesh&, const GridOptions&, BuildStats&)>
AcceleratorInfo grid_info(const char* name, const char* help, bool with_res, bool with_top) {
  AcceleratorInfo info{name, help, grid_param_infos(with_res, with_top),
                       [name, with_res, with_top](const Params& p) -> std::unique_ptr<Accelerator> {
                         return std::make_unique<GridAccel<Grid, kBuild>>(
                             parse_grid_options(name, p, with_res, with_top));
                       }};
  complete_grid_info(info);
  return info;
}

}  // namespace

AcceleratorInfo grid_accelerator_info() {
  return grid_info<UniformGrid, build_uniform_grid>(
      "grid", "dense uniform grid, n^(1/3) rule, exact SAT assignment, 6-connected 3D-DDA (Amanatides & Woo 1987)",
      true, false);
}

AcceleratorInfo hashgrid_accelerator_info() {
  return grid_info<HashGrid, build_hash_grid>(
      "hashgrid", "uniform grid storing only occupied cells in a hash table (open addressing), same 3D-DDA as grid",
      true, false);
}

AcceleratorInfo grid2_accelerator_info() {
  return grid_info<TwoLevelGrid, build_two_level_grid>(
      "grid2", "two-level grid: coarse top grid, n^(1/3)-rule sub-grid per non-empty cell, nested 3D-DDA", false,
      true);
}

}  // namespace raylab
