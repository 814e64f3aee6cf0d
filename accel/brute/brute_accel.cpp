#include "accel/brute/brute_accel.h"

#include "accel/core/batch_accelerator.h"
#include "accel/core/hit_recorder.h"
#include "accel/core/leaf_triangle.h"
#include "accel/core/structure_info.h"
#include "accel/core/triangle_test_param.h"

namespace raylab {

namespace {

class BruteAccel final : public BatchAccelerator<BruteAccel> {
 public:
  explicit BruteAccel(TriangleTest test) : BatchAccelerator(test) {}

  template <TriangleTest kTest, bool kAnyHit, bool kCount>
  Hit trace(const Ray& ray, TraversalStats* stats) const {
    HitRecorder<kAnyHit, kCount> rec(ray, stats);
    // Before build() there are no triangles: every ray misses.
    if (tris_.empty() || !ray_is_valid(ray)) return rec.hit();
    const TrianglePrecompute<kTest> pre(ray);
    rec.count_leaf(tris_.size());  // one leaf: no steps
    // In id order, strictly nearer only: among exact ties the lowest id wins.
    intersect_leaf(pre, ray, tris_.data(), static_cast<uint32_t>(tris_.size()), rec);
    return rec.hit();
  }
  // One leaf holding every triangle: its picture is the scene's box.
  void outline(int /*max_depth*/, StructureOutline& out) const override {
    out.what = "one leaf (the scene box)";
    if (!bounds_.is_empty()) out.add(OutlineBox{bounds_, 0, true});
  }

 protected:
  BuildStats build_impl(const TriangleMesh& mesh) override {
    tris_ = copy_leaf_triangles(mesh);
    bounds_ = mesh.bounds();
    BuildStats s;
    s.leaves = mesh.num_triangles() > 0 ? 1 : 0;
    s.nodes = s.leaves;
    s.bytes = tris_.size() * sizeof(LeafTriangle);
    return s;
  }

 private:
  std::vector<LeafTriangle> tris_;
  Aabb bounds_;
};

}  // namespace

AcceleratorInfo brute_accelerator_info() {
  AcceleratorInfo info = structure_info("brute",
                       "tests every triangle (ground truth for small scenes)",
                       {},
                       [](const Params& p) -> std::unique_ptr<Accelerator> {
                         return std::make_unique<BruteAccel>(parse_triangle_test(p));
                       });
  info.caps.quadratic = true;
  info.cover = {"brute:tri=mt"};
  info.build_peak_bytes_per_triangle = 45;  // from its layout (40-byte leaf triangles); not measured at 10^7
  return info;
}

}  // namespace raylab
