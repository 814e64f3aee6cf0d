// Hybrid structures (accel/hybrid): agreement with brute force on soups,
// secondary rays and rays starting on top-grid cell borders; cells holding
// one triangle; statistics.
#include <gtest/gtest.h>

#include "accel/hybrid/top_grid.h"
#include "accel/registry.h"
#include "base/mesh_shapes.h"
#include "base/pcg.h"
#include "scenes/procedural.h"
#include "tests/accel_test_util.h"
#include "tests/brute_agreement.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

const char* const kHybridSpecs[] = {"hybrid", "hybrid:inner=kdtree", "hybrid:inner=entry", "hybrid:density=2,leaf=1",
                                    "hybrid:inner=entry,density=1"};

TEST(Hybrid, AgreesWithBruteForceOnSoupAndSecondaryRays) {
  const TriangleMesh mesh = make_triangle_soup(800, 5).mesh;
  const std::vector<Ray> primary = test::rays_at_triangles(mesh, 1500, 3);
  const std::vector<Ray> secondary = test::secondary_rays(mesh, primary, 4);
  ASSERT_GT(secondary.size(), 500u);
  test::expect_specs_agree_with_brute(kHybridSpecs, mesh, {primary, secondary});
}

// Origins exactly on top-grid cell boundaries (the boundaries the walk and
// the entry grid use), heading along the axes, along the boundary plane and
// in random directions.
TEST(Hybrid, RaysStartingOnCellBorders) {
  const TriangleMesh mesh = make_triangle_soup(600, 11).mesh;
  for (const double density : {0.0625, 1.0}) {
    const TopGrid top = build_top_grid(mesh, density, false);
    ASSERT_GT(top.dda.cells(), 1u);
    Pcg32 rng(17, 1);
    std::vector<Ray> rays;
    for (int i = 0; i < 1500; ++i) {
      Vec3f o;
      for (int a = 0; a < 3; ++a) o[a] = static_cast<float>(top.dda.lo[a] + rng.uniform() * (top.dda.hi[a] - top.dda.lo[a]));
      const int axis = static_cast<int>(rng.next() % 3);
      o[axis] = static_cast<float>(top.dda.boundary(axis, rng.next() % (top.dda.res[axis] + 1)));
      Vec3f d = test::random_direction(rng);
      switch (i % 4) {
        case 0: d = Vec3f::Zero(), d[axis] = (rng.next() % 2) ? 1.0f : -1.0f; break;  // across the border
        case 1: d[axis] = (rng.next() % 2) ? 0.0f : -0.0f; break;                      // within the border plane
        default: break;
      }
      if (d.squaredNorm() == 0.0f) d[(axis + 1) % 3] = 1.0f;
      rays.emplace_back(o, d, (i % 5 == 0) ? 1e-3f : 0.0f);
    }
    for (const char* inner : {"bvh", "kdtree", "entry"}) {
      const std::string spec = std::string("hybrid:inner=") + inner + ",density=" + std::to_string(density);
      auto a = make_accelerator(spec);
      a->build(mesh);
      std::string first;
      EXPECT_EQ(test::count_brute_mismatches(*a, mesh, rays, &first), 0u) << spec << " density " << density << ": " << first;
    }
  }
}

// Eight small triangles near the corners of a box, one per top cell (2x2x2):
// every non-empty cell's tree holds a single triangle.
TEST(Hybrid, CellsWithOneTriangle) {
  TriangleMesh mesh;
  for (int i = 0; i < 8; ++i) {
    const Vec3f c(i & 1 ? 9.0f : 1.0f, i & 2 ? 9.0f : 1.0f, i & 4 ? 9.0f : 1.0f);
    append_triangle(mesh, c + Vec3f(-0.5f, -0.5f, 0), c + Vec3f(0.5f, -0.5f, 0), c + Vec3f(0, 0.5f, 0));
  }
  for (const char* spec : {"hybrid:density=1", "hybrid:inner=kdtree,density=1"}) {
    auto a = make_accelerator(spec);
    const BuildStats s = a->build(mesh);
    EXPECT_EQ(s.extra.at("top_cells"), 8.0) << spec;
    EXPECT_EQ(s.extra.at("trees"), 8.0) << spec;
    EXPECT_EQ(s.extra.at("refs_per_triangle"), 1.0) << spec;
    for (uint32_t i = 0; i < 8; ++i) {
      const Vec3f c(i & 1 ? 9.0f : 1.0f, i & 2 ? 9.0f : 1.0f, i & 4 ? 9.0f : 1.0f);
      const Hit h = a->intersect1(Ray(c + Vec3f(0, 0, -0.25f), Vec3f(0, 0, 1)));
      ASSERT_TRUE(h.valid()) << spec << " triangle " << i;
      EXPECT_EQ(h.prim, i) << spec;
      EXPECT_EQ(h.t, 0.25f) << spec;
      // Through the centre of the box: crosses empty cells only.
      EXPECT_FALSE(a->occluded1(Ray(Vec3f(5, 5, -20), Vec3f(0, 0, 1)))) << spec;
    }
    std::string first;
    const auto rays = test::rays_at_triangles(mesh, 600, 21);
    EXPECT_EQ(test::count_brute_mismatches(*a, mesh, rays, &first), 0u) << spec << ": " << first;
  }
}

TEST(Hybrid, ParametersAndStatistics) {
  EXPECT_THROW(make_accelerator("hybrid:inner=octree"), SpecError);
  EXPECT_THROW(make_accelerator("hybrid:density=0"), SpecError);
  EXPECT_THROW(make_accelerator("hybrid:inner=kdtree,leaf=2"), SpecError);
  EXPECT_THROW(make_accelerator("hybrid:top=octree"), SpecError);
  const TriangleMesh mesh = make_triangle_soup(2000, 2).mesh;
  auto coarse = make_accelerator("hybrid:density=0.01");
  auto fine = make_accelerator("hybrid:density=1");
  const BuildStats sc = coarse->build(mesh), sf = fine->build(mesh);
  EXPECT_LT(sc.extra.at("top_cells"), sf.extra.at("top_cells"));
  EXPECT_GT(sc.extra.at("tree_nodes"), 0.0);
  EXPECT_GE(sf.extra.at("refs_per_triangle"), 1.0);
  EXPECT_GT(sc.bytes, 0u);
  auto entry = make_accelerator("hybrid:inner=entry");
  const BuildStats se = entry->build(mesh);
  EXPECT_GT(se.extra.at("entry_avg_depth"), 0.0);
}

}  // namespace
}  // namespace raylab
