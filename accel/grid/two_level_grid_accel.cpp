#include "accel/grid/grid_accelerator.h"
#include "accel/grid/grid_accels.h"
#include "accel/grid/traverse_two_level_grid.h"
#include "accel/grid/two_level_grid.h"
#include "accel/util/timer.h"

namespace raylab {

namespace {

class TwoLevelGridAccel final : public GridAccelerator<TwoLevelGridAccel> {
 public:
  explicit TwoLevelGridAccel(const GridOptions& opt) : GridAccelerator(opt.test), opt_(opt) {}

  BuildStats build(const TriangleMesh& mesh) override {
    mesh.validate();
    Timer timer;
    BuildStats s;
    grid_ = build_two_level_grid(mesh, opt_, s);
    view_ = TwoLevelGridView{grid_.top,          grid_.top_cells.data(), grid_.contents.data(), grid_.offsets.data(),
                             grid_.refs.data(),  grid_.tris.data(),      grid_.empty};
    s.build_ms = timer.ms();
    return s;
  }

  template <TriangleTest kTest, bool kAnyHit, bool kCount>
  Hit trace(const Ray& ray, TraversalStats* stats) const {
    return traverse_two_level_grid<kTest, kAnyHit, kCount>(view_, ray, stats);
  }

 private:
  GridOptions opt_;
  TwoLevelGrid grid_;
  TwoLevelGridView view_;
};

}  // namespace

AcceleratorInfo grid2_accelerator_info() {
  return AcceleratorInfo{
      "grid2",
      "two-level grid: coarse top grid, n^(1/3)-rule sub-grid per non-empty cell, nested 3D-DDA",
      grid_param_infos(false, true),
      [](const Params& p) -> std::unique_ptr<Accelerator> {
        return std::make_unique<TwoLevelGridAccel>(parse_grid_options("grid2", p, false, true));
      }};
}

}  // namespace raylab
