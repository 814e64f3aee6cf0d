// hgrid, loose_octree and grid:storage=implicit: their own corner cases
// (hgrid triangles on cell borders and at the largest level; loose children
// overlapping each other; implicit-grid bit sets across 64-bit word
// boundaries), each checked bit for bit against brute force, and their
// reported figures.
#include <gtest/gtest.h>

#include <cmath>

#include "accel/registry.h"
#include "scenes/procedural.h"
#include "tests/accel_agreement.h"

namespace raylab {
namespace {

// ------------------------------------------------------------ hgrid

// Small triangles centred exactly on cell borders of the finest level
// (lattice points of the level's cells), and one huge triangle that alone
// occupies the largest level.
TriangleMesh border_scene() {
  TriangleMesh m;
  const float s = 0.25f;  // triangle extent: the finest cell side
  for (int i = 0; i < 8; ++i)
    for (int j = 0; j < 8; ++j) {
      const Vec3f c(static_cast<float>(i) * s, static_cast<float>(j) * s, 0.5f * static_cast<float>((i + j) % 3));
      test::add_triangle(m, c + Vec3f(-0.5f * s, -0.5f * s, 0), c + Vec3f(0.5f * s, -0.5f * s, 0.1f * s),
                         c + Vec3f(0, 0.5f * s, -0.1f * s));
    }
  test::add_triangle(m, Vec3f(-10, -10, -1), Vec3f(30, -10, -1), Vec3f(-10, 30, 2));  // the largest level
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

// ------------------------------------------------------------ loose octree

// Triangles straddling the dividing planes at every level land in children
// whose loose boxes overlap their siblings': rays through the overlaps.
TEST(LooseOctree, OverlappingChildrenKeepClosestHits) {
  TriangleMesh mesh;
  Pcg32 rng(2, 2);
  for (int i = 0; i < 600; ++i) {
    // Centres near the planes x, y, z = 0 (the root's) and +-0.5 (level 1).
    Vec3f c(0.5f * static_cast<float>(static_cast<int>(rng.next() % 3) - 1) + 0.02f * (rng.uniform() - 0.5f),
            2.0f * rng.uniform() - 1.0f, 2.0f * rng.uniform() - 1.0f);
    if (i % 2) std::swap(c.x(), c.y());
    const float r = 0.01f + 0.1f * rng.uniform();
    test::add_triangle(mesh, c + r * test::random_direction(rng), c + r * test::random_direction(rng),
                       c + r * test::random_direction(rng));
  }
  auto rays = test::rays_at_triangles(mesh, 2000, 3);
  for (const char* spec : {"loose_octree", "loose_octree:k=1", "loose_octree:k=4,leaf=1"}) {
    std::string first;
    EXPECT_EQ(test::mismatches_vs_brute(spec, mesh, rays, &first), 0u) << spec << ": " << first;
  }
  const BuildStats s = make_accelerator("loose_octree")->build(mesh);
  EXPECT_EQ(s.extra.at("refs_per_triangle"), 1.0);
  EXPECT_GT(s.max_depth, 2);
  const BuildStats tight = make_accelerator("loose_octree:k=1")->build(mesh);
  // k = 1: straddling triangles cannot go down, so more stay high up.
  EXPECT_GT(tight.extra.at("inner_references"), s.extra.at("inner_references"));
}

TEST(LooseOctree, ProceduralScenesMatchBruteForce) {
  for (const TriangleMesh& mesh : {make_cornell_box().mesh, make_uv_sphere(24, 12)}) {
    const auto rays = test::rays_at_triangles(mesh, 1200, 5);
    std::string first;
    EXPECT_EQ(test::mismatches_vs_brute("loose_octree", mesh, rays, &first), 0u) << first;
  }
}

TEST(LooseOctree, BadParametersAreRejected) {
  for (const char* spec : {"loose_octree:k=0.5", "loose_octree:k=5", "loose_octree:leaf=0", "loose_octree:max_depth=21"})
    EXPECT_THROW(make_accelerator(spec), SpecError) << spec;
}

// ------------------------------------------------------------ implicit grid

// 130 triangles: ids 63/64 and 127/128 sit on either side of a word
// boundary, in the same cells; the AND must find each.
TEST(ImplicitGrid, BitSetsAcrossWordBoundaries) {
  TriangleMesh mesh;
  for (int i = 0; i < 130; ++i) {
    const float z = static_cast<float>(i) * 0.01f;
    const float x = (i % 64 == 63 || i % 64 == 0) ? 0.5f : static_cast<float>(i % 13) * 0.07f;
    test::add_triangle(mesh, Vec3f(x, 0, z), Vec3f(x + 0.05f, 0, z), Vec3f(x, 0.05f, z + 0.001f));
  }
  std::vector<Ray> rays;
  for (const int id : {62, 63, 64, 65, 126, 127, 128, 129}) {
    const Vec3f p = (mesh.vertex(id, 0) + mesh.vertex(id, 1) + mesh.vertex(id, 2)) / 3.0f;
    rays.emplace_back(p + Vec3f(0, 0, -3), Vec3f(0, 0, 1));
    rays.emplace_back(p + Vec3f(0, 0, 3), Vec3f(0, 0, -1));
    rays.emplace_back(p + Vec3f(0, -3, 0.0005f), Vec3f(0, 1, 0));
  }
  const auto more = test::rays_at_triangles(mesh, 800, 8);
  rays.insert(rays.end(), more.begin(), more.end());
  for (const char* spec : {"grid:storage=implicit", "grid:storage=implicit,res=3x3x40", "grid:storage=implicit,res=1x1x1"}) {
    std::string first;
    EXPECT_EQ(test::mismatches_vs_brute(spec, mesh, rays, &first), 0u) << spec << ": " << first;
  }
  const BuildStats s = make_accelerator("grid:storage=implicit,res=3x3x40")->build(mesh);
  EXPECT_EQ(s.extra.at("slab_words"), 3.0);
  EXPECT_EQ(s.extra.at("slabs"), 46.0);
  EXPECT_GE(static_cast<double>(s.bytes), 46.0 * 3 * 8);
}

TEST(ImplicitGrid, MatchesBruteForceAndRejectsAssign) {
  const TriangleMesh mesh = make_triangle_soup(500, 3).mesh;
  const auto rays = test::rays_at_triangles(mesh, 1200, 1);
  std::string first;
  EXPECT_EQ(test::mismatches_vs_brute("grid:storage=implicit", mesh, rays, &first), 0u) << first;
  EXPECT_THROW(make_accelerator("grid:storage=implicit,assign=exact"), SpecError);
  EXPECT_THROW(make_accelerator("grid:storage=sparse"), SpecError);
}

}  // namespace
}  // namespace raylab
