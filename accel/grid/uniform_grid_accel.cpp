#include "accel/grid/grid_accelerator.h"
#include "accel/grid/grid_accels.h"
#include "accel/grid/traverse_uniform_grid.h"
#include "accel/grid/uniform_grid.h"
#include "accel/util/timer.h"

namespace raylab {

namespace {

class UniformGridAccel final : public GridAccelerator<UniformGridAccel> {
 public:
  explicit UniformGridAccel(const GridOptions& opt) : GridAccelerator(opt.test), opt_(opt) {}

  BuildStats build(const TriangleMesh& mesh) override {
    mesh.validate();
    Timer timer;
    BuildStats s;
    grid_ = build_uniform_grid(mesh, opt_, s);
    view_ = UniformGridView{grid_.dda, grid_.lists.offsets.data(), grid_.lists.refs.data(), grid_.tris.data(),
                            grid_.empty};
    s.build_ms = timer.ms();
    return s;
  }

  template <TriangleTest kTest, bool kAnyHit, bool kCount>
  Hit trace(const Ray& ray, TraversalStats* stats) const {
    return traverse_uniform_grid<kTest, kAnyHit, kCount>(view_, ray, stats);
  }

 private:
  GridOptions opt_;
  UniformGrid grid_;
  UniformGridView view_;
};

}  // namespace

AcceleratorInfo grid_accelerator_info() {
  return AcceleratorInfo{
      "grid",
      "dense uniform grid, n^(1/3) rule, exact SAT assignment, 6-connected 3D-DDA (Amanatides & Woo 1987)",
      grid_param_infos(true, false),
      [](const Params& p) -> std::unique_ptr<Accelerator> {
        return std::make_unique<UniformGridAccel>(parse_grid_options("grid", p, true, false));
      }};
}

}  // namespace raylab
