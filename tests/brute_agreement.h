#pragma once
// Exact agreement with brute force, shared by the structure tests
// (test_kdtree.cpp, and the others through accel_agreement.h): the same
// watertight kernel on the same triangles, so a node or cell the walk misses
// shows up as a different distance (compared bit for bit); the triangle may
// differ only at exactly equal distances.
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include "accel/registry.h"
#include "base/pcg.h"
#include "tests/test_util.h"

namespace raylab::test {

inline void add_triangle(TriangleMesh& m, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  const auto base = static_cast<uint32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), {a, b, c});
  m.triangles.push_back({base, base + 1, base + 2});
}

inline std::string describe_ray(const Ray& r) {
  char buf[256];
  std::snprintf(buf, sizeof(buf), "org (%a %a %a) dir (%a %a %a) t [%a %a]", r.org.x(), r.org.y(), r.org.z(),
                r.dir.x(), r.dir.y(), r.dir.z(), r.tmin, r.tmax);
  return buf;
}

// Rays whose closest hit, occlusion or instrumented-kernel answer differs
// from brute force's (`ref`, `ref_occ`, computed once for several
// structures): the same hit or miss, the same distance bit for bit, and the
// same triangle unless another one is hit at exactly that distance. `first`
// describes the first.
inline size_t count_brute_mismatches(const Accelerator& accel, std::span<const Hit> ref,
                                     std::span<const uint8_t> ref_occ, std::span<const Ray> rays,
                                     std::string* first = nullptr) {
  const size_t n = rays.size();
  std::vector<Hit> a(n), c(n);
  std::vector<uint8_t> occ(n);
  accel.intersect(rays, a);
  TraversalStats st;
  accel.intersect(rays, c, &st);
  accel.occluded(rays, occ);
  size_t bad = 0;
  for (size_t i = 0; i < n; ++i) {
    const bool same = a[i].valid() == ref[i].valid() && (!a[i].valid() || a[i].t == ref[i].t);
    const bool same_counted = c[i].valid() == a[i].valid() && c[i].t == a[i].t && c[i].prim == a[i].prim;
    if (same && same_counted && occ[i] == ref_occ[i]) continue;
    if (bad++ == 0 && first) {
      char buf[200];
      std::snprintf(buf, sizeof(buf), " -> (%d, t %a, prim %u) brute (%d, t %a, prim %u) occluded %d brute %d",
                    a[i].valid(), a[i].t, a[i].prim, ref[i].valid(), ref[i].t, ref[i].prim, occ[i], ref_occ[i]);
      *first = describe_ray(rays[i]) + buf;
    }
  }
  return bad;
}

inline size_t count_brute_mismatches(const Accelerator& accel, const TriangleMesh& mesh, std::span<const Ray> rays,
                                     std::string* first = nullptr) {
  auto brute = make_accelerator("brute");
  brute->build(mesh);
  std::vector<Hit> ref(rays.size());
  std::vector<uint8_t> ref_occ(rays.size());
  brute->intersect(rays, ref);
  brute->occluded(rays, ref_occ);
  return count_brute_mismatches(accel, ref, ref_occ, rays, first);
}

}  // namespace raylab::test
