// libFuzzer target: ray input. Every 32 bytes of input are one ray (origin,
// direction, tmin, tmax as raw floats: NaN, infinities, denormals, -0 all
// occur), traced by every accelerator on a small scene with closed meshes,
// thin and degenerate triangles. Checked for every ray and accelerator:
//  - an invalid ray (ray_is_valid false, which includes tmin > tmax) is a miss and not occluded;
//  - a hit names an existing triangle at a distance t in [tmin, tmax];
//  - the any-hit answer agrees with the closest hit (occluded iff a hit);
//    not checked for the reference (Embree), whose any-hit and closest-hit kernels can
//    disagree for directions near FLT_MIN (a quirk of the reference).
// A violation aborts (reported by libFuzzer with the input that caused it).
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "accel/registry.h"
#include "scenes/procedural.h"

namespace {

struct Fixture {
  raylab::TriangleMesh mesh;
  std::vector<std::unique_ptr<raylab::Accelerator>> accels;
  std::vector<bool> reference;  // per accelerator: the registry's reference (Embree)

  Fixture() {
    using namespace raylab;
    mesh = make_cornell_box().mesh;
    for (auto& v : mesh.vertices) v *= 1.0f / 550.0f;  // unit-sized, so fuzzed rays often meet it
    mesh.append(make_uv_sphere(12, 6, Vec3f(0.5f, 0.5f, 0.5f), 0.2f));
    TriangleMesh odd;
    odd.vertices = {Vec3f(0.1f, 0.1f, 0.1f), Vec3f(0.1f, 0.1f, 0.1f), Vec3f(0.9f, 0.9f, 0.9f),
                    Vec3f(0.2f, 0.2f, 0.2f), Vec3f(0.9f, 0.1f, 0.5f), Vec3f(0.9f, 0.1f, 0.5001f)};
    odd.triangles = {{0, 1, 2}, {0, 3, 2}, {4, 5, 2}};  // zero area, collinear, needle
    mesh.append(odd);
    // Every structure with its defaults and every variant the registry
    // asks to cover (layouts, builders, kernels).
    for (const auto& s : coverage_specs()) {
      accels.push_back(make_accelerator(s));
      reference.push_back(accelerator_info(Spec::parse(s).name).caps.reference);
      accels.back()->build(mesh);
    }
  }
};

[[noreturn]] void fail(const std::string& accel, const raylab::Ray& r, const char* what) {
  std::fprintf(stderr, "fuzz_rays: %s: %s (org %a %a %a dir %a %a %a t [%a, %a])\n", accel.c_str(), what, r.org.x(),
               r.org.y(), r.org.z(), r.dir.x(), r.dir.y(), r.dir.z(), r.tmin, r.tmax);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace raylab;
  static Fixture fx;
  constexpr size_t kRecord = 8 * sizeof(float);
  std::vector<Ray> rays;
  for (size_t off = 0; off + kRecord <= size && rays.size() < 64; off += kRecord) {
    float f[8];
    std::memcpy(f, data + off, kRecord);
    rays.push_back(Ray(Vec3f(f[0], f[1], f[2]), Vec3f(f[3], f[4], f[5]), f[6], f[7]));
  }
  if (rays.empty()) return 0;
  std::vector<Hit> hits(rays.size());
  std::vector<uint8_t> occ(rays.size());
  for (const auto& a : fx.accels) {
    a->intersect(rays, hits);
    a->occluded(rays, occ);
    // The reference's any-hit may legitimately find another triangle than its closest hit.
    const bool is_reference = fx.reference[&a - fx.accels.data()];
    for (size_t i = 0; i < rays.size(); ++i) {
      const Ray& r = rays[i];
      const Hit& h = hits[i];
      const bool valid = ray_is_valid(r);
      if (!valid && (h.valid() || occ[i])) fail(a->spec(), r, "an invalid ray hit something");
      if (h.valid()) {
        if (h.prim >= fx.mesh.num_triangles()) fail(a->spec(), r, "hit names a triangle that does not exist");
        if (!(h.t >= r.tmin && h.t <= r.tmax)) fail(a->spec(), r, "hit distance outside [tmin, tmax]");
      }
      if (!is_reference && static_cast<bool>(occ[i]) != h.valid()) fail(a->spec(), r, "any-hit answer contradicts the closest hit");
    }
  }
  return 0;
}
