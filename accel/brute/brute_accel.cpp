#include "accel/brute/brute_accel.h"

#include "accel/core/intersect_triangle.h"
#include "accel/util/timer.h"

namespace raylab {

namespace {

class BruteAccel final : public Accelerator {
 public:
  explicit BruteAccel(TriangleTest test) : test_(test) {}

  BuildStats build(const TriangleMesh& mesh) override {
    Timer timer;
    mesh.validate();
    mesh_ = &mesh;
    BuildStats s;
    s.build_ms = timer.ms();
    s.leaves = mesh.num_triangles() > 0 ? 1 : 0;
    s.nodes = s.leaves;
    return s;
  }

  void intersect(std::span<const Ray> rays, std::span<Hit> hits, TraversalStats* stats) const override {
    dispatch_triangle_test(test_, [&]<TriangleTest kTest>() {
      for (size_t i = 0; i < rays.size(); ++i) hits[i] = trace<kTest, false>(rays[i], stats);
    });
  }

  void occluded(std::span<const Ray> rays, std::span<uint8_t> occ, TraversalStats* stats) const override {
    dispatch_triangle_test(test_, [&]<TriangleTest kTest>() {
      for (size_t i = 0; i < rays.size(); ++i) occ[i] = trace<kTest, true>(rays[i], stats).valid() ? 1 : 0;
    });
  }

 private:
  template <TriangleTest kTest, bool kAnyHit>
  Hit trace(const Ray& ray, TraversalStats* stats) const {
    Hit hit;
    if (stats) stats->rays++;
    if (!ray_is_valid(ray)) return hit;
    const TrianglePrecompute<kTest> pre(ray);
    float tmax = ray.tmax;
    const size_t n = mesh_->num_triangles();
    for (size_t i = 0; i < n; ++i) {
      const auto& tri = mesh_->triangles[i];
      float t, u, v;
      if (pre.intersect(ray, mesh_->vertices[tri[0]], mesh_->vertices[tri[1]], mesh_->vertices[tri[2]], ray.tmin,
                        tmax, t, u, v)) {
        // Strictly nearer only: among exact ties the lowest id wins.
        if (t < tmax || !hit.valid()) {
          hit = Hit{t, u, v, static_cast<uint32_t>(i)};
          tmax = t;
          if constexpr (kAnyHit) break;
        }
      }
    }
    if (stats) stats->triangle_tests += n;
    return hit;
  }

  TriangleTest test_;
  const TriangleMesh* mesh_ = nullptr;
};

}  // namespace

AcceleratorInfo brute_accelerator_info() {
  return AcceleratorInfo{"brute",
                         "tests every triangle (ground truth for small scenes)",
                         {{"tri", "watertight", "triangle test: watertight (Woop et al. 2013) or mt (Moller-Trumbore)"}},
                         [](const Params& p) -> std::unique_ptr<Accelerator> {
                           const auto& t = p.choice("tri", {"watertight", "mt"});
                           return std::make_unique<BruteAccel>(t == "mt" ? TriangleTest::MollerTrumbore
                                                                         : TriangleTest::Watertight);
                         }};
}

}  // namespace raylab
