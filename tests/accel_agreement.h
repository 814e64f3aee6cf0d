#pragma once
// Agreement with brute force for the structure tests above the structures
// layer (octree family, hgrid, hybrid, BSP, spheres): the same watertight
// kernel on the same triangles, so a missed cell or node shows up as a
// different distance (compared bit for bit), and the triangle may differ
// only at exactly equal distances.
#include <gtest/gtest.h>

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

// Each spec's structure agrees with brute force on every ray set given.
inline void expect_specs_agree_with_brute(std::span<const char* const> specs, const TriangleMesh& mesh,
                                          std::initializer_list<std::span<const Ray>> ray_sets) {
  for (const char* spec : specs) {
    auto a = make_accelerator(spec);
    a->build(mesh);
    for (const auto& rays : ray_sets) {
      std::string first;
      EXPECT_EQ(count_brute_mismatches(*a, mesh, rays, &first), 0u) << spec << ": " << first;
    }
  }
}

}  // namespace raylab::test
