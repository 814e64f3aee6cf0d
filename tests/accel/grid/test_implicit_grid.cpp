// The implicit grid (grid:storage=implicit): bit sets across 64-bit word
// boundaries, checked bit for bit against brute force, and its reported
// figures.
#include <gtest/gtest.h>

#include "accel/registry.h"
#include "base/mesh_shapes.h"
#include "scenes/procedural.h"
#include "tests/accel_test_util.h"
#include "tests/brute_agreement.h"

namespace raylab {
namespace {

// 130 triangles: ids 63/64 and 127/128 sit on either side of a word
// boundary, in the same cells; the AND must find each.
TEST(ImplicitGrid, BitSetsAcrossWordBoundaries) {
  TriangleMesh mesh;
  for (int i = 0; i < 130; ++i) {
    const float z = static_cast<float>(i) * 0.01f;
    const float x = (i % 64 == 63 || i % 64 == 0) ? 0.5f : static_cast<float>(i % 13) * 0.07f;
    append_triangle(mesh, Vec3f(x, 0, z), Vec3f(x + 0.05f, 0, z), Vec3f(x, 0.05f, z + 0.001f));
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
