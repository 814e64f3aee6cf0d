#pragma once
// Agreement with brute force for the hybrid, BSP and sphere tests: the same
// watertight kernel on the same triangles, so a missed cell or node shows up
// as a different distance (compared bit for bit), and the triangle may
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

// Rays whose closest hit, occlusion or instrumented-kernel answer differs
// from brute force; `first` describes the first.
inline size_t count_brute_mismatches(const Accelerator& accel, const TriangleMesh& mesh, std::span<const Ray> rays,
                                     std::string* first = nullptr) {
  auto brute = make_accelerator("brute");
  brute->build(mesh);
  const size_t n = rays.size();
  std::vector<Hit> ref(n), a(n), c(n);
  std::vector<uint8_t> oref(n), oa(n);
  brute->intersect(rays, ref);
  brute->occluded(rays, oref);
  accel.intersect(rays, a);
  TraversalStats st;
  accel.intersect(rays, c, &st);
  accel.occluded(rays, oa);
  size_t bad = 0;
  for (size_t i = 0; i < n; ++i) {
    const bool same = a[i].valid() == ref[i].valid() && (!a[i].valid() || a[i].t == ref[i].t);
    const bool same_counted = c[i].valid() == a[i].valid() && c[i].t == a[i].t && c[i].prim == a[i].prim;
    if (same && same_counted && oa[i] == oref[i]) continue;
    if (bad++ == 0 && first) {
      char buf[400];
      const Ray& r = rays[i];
      std::snprintf(buf, sizeof(buf),
                    "org (%a %a %a) dir (%a %a %a) t [%a %a] -> (%d, t %a) brute (%d, t %a) occluded %d brute %d",
                    r.org.x(), r.org.y(), r.org.z(), r.dir.x(), r.dir.y(), r.dir.z(), r.tmin, r.tmax, a[i].valid(),
                    a[i].t, ref[i].valid(), ref[i].t, oa[i], oref[i]);
      *first = buf;
    }
  }
  return bad;
}

// Rays aimed at points of the mesh's triangles (interior, edges, vertices)
// from random directions, plus random rays through the box.
inline std::vector<Ray> rays_at_triangles(const TriangleMesh& mesh, size_t count, uint64_t seed) {
  Pcg32 rng(seed, 7);
  const Aabb box = mesh.bounds();
  const float diag = std::max(box.diagonal().norm(), 1e-3f);
  std::vector<Ray> rays;
  for (size_t i = 0; i < count; ++i) {
    if (i % 3 == 2 || mesh.num_triangles() == 0) {
      const Vec3f o = box.center() + 0.75f * diag * Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f);
      rays.emplace_back(o, random_direction(rng));
      continue;
    }
    const size_t tri = rng.next() % mesh.num_triangles();
    float u = rng.uniform(), v = rng.uniform();
    if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
    if (rng.next() % 4 == 0) u = static_cast<float>(rng.next() % 2), v = 0.0f;
    const Vec3f p = (1.0f - u - v) * mesh.vertex(tri, 0) + u * mesh.vertex(tri, 1) + v * mesh.vertex(tri, 2);
    const Vec3f o = p + diag * (0.05f + rng.uniform()) * random_direction(rng);
    rays.emplace_back(o, p - o);
  }
  return rays;
}

// Secondary rays: from the hit points of `primary` (closest hits by brute
// force) in random directions, tmin = 0 (rays starting on a surface).
inline std::vector<Ray> secondary_rays(const TriangleMesh& mesh, std::span<const Ray> primary, uint64_t seed) {
  auto brute = make_accelerator("brute");
  brute->build(mesh);
  std::vector<Hit> hits(primary.size());
  brute->intersect(primary, hits);
  Pcg32 rng(seed, 9);
  std::vector<Ray> rays;
  for (size_t i = 0; i < primary.size(); ++i)
    if (hits[i].valid()) rays.emplace_back(primary[i].at(hits[i].t), random_direction(rng), 0.0f);
  return rays;
}

}  // namespace raylab::test
