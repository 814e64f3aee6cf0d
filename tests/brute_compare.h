#pragma once
// Exact agreement with brute force for the octree family's tests (octree,
// loose_octree, hgrid): the same watertight kernel on the same triangles, so
// a node or cell the walk misses shows up as a different distance.
#include <span>
#include <string>
#include <vector>

#include "tests/brute_agreement.h"

namespace raylab::test {

// count_brute_mismatches() for a structure made from `spec`.
inline size_t mismatches_vs_brute(const std::string& spec, const TriangleMesh& mesh, std::span<const Ray> rays,
                                  std::string* first = nullptr) {
  auto accel = make_accelerator(spec);
  accel->build(mesh);
  return count_brute_mismatches(*accel, mesh, rays, first);
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
