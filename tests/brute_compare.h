#pragma once
// Exact agreement with brute force for the octree family's tests (octree,
// loose_octree, hgrid): the same watertight kernel on the same triangles, so
// a node or cell the walk misses shows up as a different distance.
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

// Rays that differ from brute force: hit or miss, distance bit for bit,
// occlusion, and the instrumented kernel against the plain one. The first
// difference is described in *first.
inline size_t mismatches_vs_brute(const std::string& spec, const TriangleMesh& mesh, std::span<const Ray> rays,
                                  std::string* first = nullptr) {
  auto brute = make_accelerator("brute");
  brute->build(mesh);
  auto accel = make_accelerator(spec);
  accel->build(mesh);
  const size_t n = rays.size();
  std::vector<Hit> ref(n), a(n), c(n);
  std::vector<uint8_t> ref_occ(n), occ(n);
  brute->intersect(rays, ref);
  brute->occluded(rays, ref_occ);
  accel->intersect(rays, a);
  TraversalStats st;
  accel->intersect(rays, c, &st);
  accel->occluded(rays, occ);
  size_t bad = 0;
  for (size_t i = 0; i < n; ++i) {
    const bool same = a[i].valid() == ref[i].valid() && (!a[i].valid() || a[i].t == ref[i].t);
    const bool same_counted = c[i].valid() == a[i].valid() && c[i].t == a[i].t && c[i].prim == a[i].prim;
    if (same && same_counted && occ[i] == ref_occ[i]) continue;
    if (bad++ == 0 && first) {
      char buf[200];
      std::snprintf(buf, sizeof(buf), " -> %s (%d, t %a, prim %u) brute (%d, t %a, prim %u) occluded %d brute %d",
                    spec.c_str(), a[i].valid(), a[i].t, a[i].prim, ref[i].valid(), ref[i].t, ref[i].prim, occ[i],
                    ref_occ[i]);
      *first = describe_ray(rays[i]) + buf;
    }
  }
  return bad;
}

// Rays aimed at points of the triangles (interior, edges, vertices) from
// random directions, plus random rays starting inside the bounds.
inline std::vector<Ray> rays_at_triangles(const TriangleMesh& mesh, size_t count, uint64_t seed) {
  Pcg32 rng(seed, 5);
  const Aabb box = mesh.bounds();
  const float diag = std::max(box.diagonal().norm(), 1e-3f);
  std::vector<Ray> rays;
  for (size_t i = 0; i < count; ++i) {
    if (i % 3 == 2) {
      const Vec3f o = box.lo + Vec3f(rng.uniform(), rng.uniform(), rng.uniform()).cwiseProduct(box.diagonal());
      rays.emplace_back(o, random_direction(rng));
      continue;
    }
    const size_t tri = rng.next() % mesh.num_triangles();
    float u = rng.uniform(), v = rng.uniform();
    if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
    if (i % 5 == 0) u = static_cast<float>(rng.next() % 2), v = 0.0f;
    const Vec3f p = (1.0f - u - v) * mesh.vertex(tri, 0) + u * mesh.vertex(tri, 1) + v * mesh.vertex(tri, 2);
    const Vec3f o = p + diag * (0.05f + rng.uniform()) * random_direction(rng);
    rays.emplace_back(o, p - o);
  }
  return rays;
}

}  // namespace raylab::test
