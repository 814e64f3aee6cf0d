// The loose octree's own corner cases (children whose loose boxes overlap
// each other), checked bit for bit against brute force, and its reported
// figures.
#include <gtest/gtest.h>

#include <utility>

#include "accel/registry.h"
#include "base/mesh_shapes.h"
#include "base/pcg.h"
#include "scenes/procedural.h"
#include "tests/accel_test_util.h"
#include "tests/brute_agreement.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

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
    append_triangle(mesh, c + r * test::random_direction(rng), c + r * test::random_direction(rng),
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

}  // namespace
}  // namespace raylab
