#include "accel/grid/grid_accelerator.h"
#include "accel/grid/grid_accels.h"
#include "accel/grid/hash_grid.h"
#include "accel/grid/traverse_hash_grid.h"
#include "accel/util/timer.h"

namespace raylab {

namespace {

class HashGridAccel final : public GridAccelerator<HashGridAccel> {
 public:
  explicit HashGridAccel(const GridOptions& opt) : GridAccelerator(opt.test), opt_(opt) {}

  BuildStats build(const TriangleMesh& mesh) override {
    mesh.validate();
    Timer timer;
    BuildStats s;
    grid_ = build_hash_grid(mesh, opt_, s);
    view_ = HashGridView{grid_.dda, &grid_.table, grid_.refs.data(), grid_.tris.data(), grid_.empty};
    s.build_ms = timer.ms();
    return s;
  }

  template <TriangleTest kTest, bool kAnyHit, bool kCount>
  Hit trace(const Ray& ray, TraversalStats* stats) const {
    return traverse_hash_grid<kTest, kAnyHit, kCount>(view_, ray, stats);
  }

 private:
  GridOptions opt_;
  HashGrid grid_;
  HashGridView view_;
};

}  // namespace

AcceleratorInfo hashgrid_accelerator_info() {
  return AcceleratorInfo{
      "hashgrid",
      "uniform grid storing only occupied cells in a hash table (open addressing), same 3D-DDA as grid",
      grid_param_infos(true, false),
      [](const Params& p) -> std::unique_ptr<Accelerator> {
        return std::make_unique<HashGridAccel>(parse_grid_options("hashgrid", p, true, false));
      }};
}

}  // namespace raylab
