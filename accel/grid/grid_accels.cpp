// The three grids behind one Accelerator shell: a grid type, its builder,
// its view (grid_view) and its walk (traverse_grid, overloaded per view).
#include "accel/grid/grid_accels.h"

#include <utility>

#include "accel/core/any_hit_order.h"
#include "accel/core/batch_accelerator.h"
#include "accel/grid/grid_outline.h"
#include "accel/grid/traverse_hash_grid.h"
#include "accel/grid/traverse_implicit_grid.h"
#include "accel/grid/traverse_two_level_grid.h"
#include "accel/grid/traverse_uniform_grid.h"

namespace raylab {

namespace {

template <typename Grid, Grid (*kBuild)(const TriangleMesh&, const GridOptions&, BuildStats&)>
class GridAccel final : public BatchAccelerator<GridAccel<Grid, kBuild>> {
 public:
  explicit GridAccel(const GridOptions& opt) : BatchAccelerator<GridAccel<Grid, kBuild>>(opt.test), opt_(opt) {}

  AnyHitOrder any_hit_order() const { return opt_.any_hit_order; }
  template <TriangleTest kTest, bool kAnyHit, bool kCount>
  Hit trace(const Ray& ray, TraversalStats* stats, bool far_first = false) const {
    return walk_in_any_hit_order<kAnyHit>(far_first, [&]<bool kFarFirst>() {
      return traverse_grid<kTest, kAnyHit, kCount, kFarFirst>(view_, ray, stats);
    });
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
AcceleratorInfo grid_info(const char* name, const char* help, bool with_res, bool with_top,
                          double build_peak_bytes_per_triangle, double scalar_build_peak_bytes_per_triangle) {
  AcceleratorInfo info{name, help, grid_param_infos(with_res, with_top),
                       [with_res, with_top](const Params& p) -> std::unique_ptr<Accelerator> {
                         return std::make_unique<GridAccel<Grid, kBuild>>(parse_grid_options(p, with_res, with_top));
                       }};
  complete_grid_info(info);
  info.build_peak_bytes_per_triangle = build_peak_bytes_per_triangle;
  info.variant_build_peaks.push_back({info.caps.scalar_variant, scalar_build_peak_bytes_per_triangle});
  return info;
}

}  // namespace

AcceleratorInfo grid_accelerator_info() {
  AcceleratorInfo info = grid_info<UniformGrid, build_uniform_grid>(
      "grid", "dense uniform grid, n^(1/3) rule, exact SAT assignment, 6-connected 3D-DDA (Amanatides & Woo 1987)",
      true, false, 360, 75);  // peak bytes per triangle: measured 357 on soup:n=10^6 (simd=0: 68 on soup:n=10^7)
  // storage=implicit (accel/grid/implicit_grid.h): the same resolution and
  // DDA, cells found as the AND of per-slab bit arrays.
  info.params.push_back({"storage", "dense",
                         "dense (a list per cell) or implicit (a bit array per x, y and z slab; "
                         "a cell's triangles = the AND of its three; bounding-box assignment)",
                         one_of({"dense", "implicit"})});
  info.params.push_back({"skip", "1",
                         "empty-space skipping: 1 = a ray in an empty cell leaves the cube of empty cells around it "
                         "in one jump (per-cell distance to the nearest occupied cell, 1 byte per cell); 0 = plain 3D-DDA",
                         boolean_flag()});
  info.make = [](const Params& p) -> std::unique_ptr<Accelerator> {
    if (p.str("storage") == "dense") {
      GridOptions opt = parse_grid_options(p, true, false);
      opt.skip = p.boolean("skip");
      return std::make_unique<GridAccel<UniformGrid, build_uniform_grid>>(opt);
    }
    if (p.given("skip")) throw SpecError("grid: skip does not apply to storage=implicit");
    if (p.given("assign")) throw SpecError("grid: assign does not apply to storage=implicit (bounding boxes by slab)");
    return std::make_unique<GridAccel<ImplicitGrid, build_implicit_grid>>(parse_grid_options(p, true, false));
  };
  info.cover.push_back("grid:storage=implicit");
  info.cover.push_back("grid:skip=0");
  info.stats.insert(info.stats.end(), {{"slabs", "storage=implicit: slab bit arrays (nx + ny + nz)"},
                                       {"slab_bits_set", "storage=implicit: set bits over all slabs"},
                                       {"slab_words", "storage=implicit: 64-bit words per slab"}});
  return info;
}

AcceleratorInfo hashgrid_accelerator_info() {
  return grid_info<HashGrid, build_hash_grid>(
      "hashgrid", "uniform grid storing only occupied cells in a hash table (open addressing), same 3D-DDA as grid",
      true, false, 470, 180);  // measured 461 on soup:n=10^6 (simd=0: 131 on soup:n=10^7, 172 on soup:n=10^6)
}

AcceleratorInfo grid2_accelerator_info() {
  return grid_info<TwoLevelGrid, build_two_level_grid>(
      "grid2", "two-level grid: coarse top grid, n^(1/3)-rule sub-grid per non-empty cell, nested 3D-DDA", false,
      true, 560, 160);  // measured 556 on soup:n=10^6 (simd=0: 145 on soup:n=10^7, 151 on soup:n=10^6)
}

}  // namespace raylab
