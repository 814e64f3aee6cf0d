// The hierarchical grid's own corner cases (triangles on cell borders and at
// the largest level), checked bit for bit against brute force, and its
// reported figures.
#include <gtest/gtest.h>

#include "accel/registry.h"
#include "base/mesh_shapes.h"
#include "scenes/procedural.h"
#include "tests/accel_test_util.h"
#include "tests/brute_agreement.h"

namespace raylab {
namespace {

// Small triangles centred exactly on cell borders of the finest level
// (lattice points of the level's cells), and one huge triangle that alone
// occupies the largest level.
TriangleMesh border_scene() {
  TriangleMesh m;
  const float s = 0.25f;  // triangle extent: the finest cell side
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) {
      const Vec3f c(static_cast<float>(i) * s, static_cast<float>(j) * s, 0.5f * static_cast<float>((i + j) % 3));
      append_triangle(m, c + Vec3f(-0.5f * s, -0.5f * s, 0), c + Vec3f(0.5f * s, -0.5f * s, 0.1f * s),
                      c + Vec3f(0, 0.5f * s, -0.1f * s));
    }
  append_triangle(m, Vec3f(-10, -10, -1), Vec3f(30, -10, -1), Vec3f(-10, 30, 2));  // the largest level
  return m;
}

TEST(Hgrid, BorderTrianglesAndTheLargestLevelMatchBruteForce) {
  const TriangleMesh mesh = border_scene();
  auto rays = test::rays_at_triangles(mesh, 1500, 4);
  // Rays along the cell borders themselves, both signs of zero.
  for (int i = 0; i < 8; ++i)
    for (const float z : {0.0f, -0.0f}) {
      rays.emplace_back(Vec3f(0.25f * static_cast<float>(i), -5, 3), Vec3f(z, 1, -0.5f));
      rays.emplace_back(Vec3f(-5, 0.25f * static_cast<float>(i) + 0.125f, 0.05f), Vec3f(1, z, z));
    }
  for (const char* spec : {"hgrid", "hgrid:neighbours=pad", "hgrid:ratio=3"}) {
    std::string first;
    EXPECT_EQ(test::mismatches_vs_brute(spec, mesh, rays, &first), 0u) << spec << ": " << first;
  }
  const BuildStats s = make_accelerator("hgrid")->build(mesh);
  EXPECT_GE(s.extra.at("occupied_levels"), 2.0);
  EXPECT_GE(s.extra.at("level_span"), 7.0);  // 40 / 0.25 = 160 = 2^7.3: the big triangle ~8 levels up
  EXPECT_EQ(make_accelerator("hgrid:neighbours=pad")->build(mesh).extra.at("refs_per_triangle"), 1.0);
  EXPECT_LE(s.extra.at("refs_per_triangle"), 27.0);
}

TEST(Hgrid, ProceduralScenesMatchBruteForce) {
  for (const TriangleMesh& mesh : {make_cornell_box().mesh, make_triangle_soup(400, 6).mesh}) {
    const auto rays = test::rays_at_triangles(mesh, 1200, 9);
    for (const char* spec : {"hgrid", "hgrid:neighbours=pad"}) {
      std::string first;
      EXPECT_EQ(test::mismatches_vs_brute(spec, mesh, rays, &first), 0u) << spec << ": " << first;
    }
  }
}

TEST(Hgrid, BadParametersAreRejected) {
  for (const char* spec : {"hgrid:ratio=1", "hgrid:ratio=17", "hgrid:neighbours=all", "hgrid:tri=x"})
    EXPECT_THROW(make_accelerator(spec), SpecError) << spec;
}

}  // namespace
}  // namespace raylab
