// The structures against Embree through the checks layer: `verify`'s
// double-precision oracle arbitrates every disagreement (checks/verify.h), on
// procedural scenes and the shared meshes. The structure tests themselves
// (raylab_tests_accel) compare with brute force and link no checks code.
#include <gtest/gtest.h>

#include "accel/registry.h"
#include "checks/classify.h"
#include "checks/verify.h"
#include "scenes/procedural.h"
#include "scenes/scene_registry.h"
#include "tests/accel_test_util.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

// A bare mesh as a lit scene (a camera framing it, a white sky).
Scene lit_scene_from_mesh(std::string name, TriangleMesh mesh) {
  Scene s = scene_from_mesh(std::move(name), std::move(mesh));
  s.view = frame_bounds(s.mesh.bounds());
  s.background = Vec3f::Constant(1.0f);
  return s;
}

// No wrong hit and no occlusion disagreement for any of `specs` on any ray set.
void expect_verified(const Scene& scene, const std::vector<std::string>& specs, VerifyOptions vo) {
  const auto records = verify_accelerators(scene, specs, vo);
  ASSERT_EQ(records.size(), specs.size() * vo.ray_sets.size());
  for (const VerifyRecord& r : records) {
    EXPECT_EQ(r.raylab_wrong, 0u) << scene.name << " " << r.accel << " " << r.ray_set;
    EXPECT_EQ(r.occlusion_disagree, 0u) << scene.name << " " << r.accel << " " << r.ray_set;
  }
}

VerifyOptions with_rays(size_t rays, int threads = 0) {
  VerifyOptions vo;
  vo.rays = rays;
  if (threads > 0) vo.threads = threads;
  return vo;
}

class EveryAcceleratorVerified : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryAcceleratorVerified, AgreesWithEmbreeAfterArbitration) {
  for (const char* scene : {"soup:n=20000,seed=3", "cornell", "sphere:segments=64,rings=32"}) {
    VerifyOptions vo = with_rays(20000);
    vo.ray_sets = {"primary", "random", "diffuse", "shadow"};
    const auto records = verify_accelerators(load_scene(scene), {GetParam()}, vo);
    ASSERT_EQ(records.size(), 4u);
    for (const auto& r : records) {
      EXPECT_EQ(r.raylab_wrong, 0u) << r.accel << " " << scene << " " << r.ray_set;
      EXPECT_EQ(r.occlusion_disagree, 0u) << r.accel << " " << scene << " " << r.ray_set;
      EXPECT_LT(r.max_rel_t_err, 1e-3) << r.accel << " " << scene << " " << r.ray_set;
      EXPECT_GT(r.rays, 1000u);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Registry, EveryAcceleratorVerified, ::testing::ValuesIn(test::specs_checked_against_brute()),
                         [](const auto& info) { return test::gtest_name(info.param); });

TEST(Embree, AgreesWithBruteForceOnSoup) {
  const TriangleMesh mesh = triangle_soup_mesh(3000, 2);
  auto e = make_accelerator("embree:robust=1");
  const BuildStats st = e->build(mesh);
  auto b = make_accelerator("brute");
  b->build(mesh);
  size_t disagree = 0;
  // Random segments (not aimed at edges, where Embree is not watertight).
  for (const Ray& r : test::segment_rays(mesh, 5000, 2)) {
    const Hit x = e->intersect1(r), y = b->intersect1(r);
    disagree += screen_closest(x, y) == Screen::Disagree;
  }
  EXPECT_LE(disagree, 2u);
  EXPECT_GT(st.bytes, 3000u * 10);
}

const std::vector<std::string> kGridSpecs = {"grid", "hashgrid", "grid2"};
const std::vector<std::string> kKdSpecs = {"kdtree", "kdtree:clip=0", "kdtree:builder=median"};

TEST(GridVerify, ProceduralScenesAgreeWithEmbree) {
  expect_verified(load_scene("cornell"), kGridSpecs, with_rays(20000, 2));
  expect_verified(load_scene("soup:n=20000,seed=4"), kGridSpecs, with_rays(20000, 2));
  expect_verified(lit_scene_from_mesh("flat", test::flat_tiles_mesh(40, 1000, 2)), kGridSpecs, with_rays(20000, 2));
  expect_verified(lit_scene_from_mesh("stadium", test::teapot_in_stadium_mesh()), kGridSpecs, with_rays(20000, 2));
}

TEST(GridVerify, SharedMeshesAgreeWithEmbree) {
  if (!test::have_shared_scenes()) GTEST_SKIP() << "../shared/scenes not present";
  for (const char* mesh : {"bunny.ply", "sponza.ply", "teapot.ply"})
    expect_verified(load_scene(test::shared_dir() + "/scenes/" + mesh), kGridSpecs, with_rays(20000, 2));
}

TEST(KdTreeVerify, AgreesWithEmbreeOnProceduralScenes) {
  expect_verified(make_cornell_box(), kKdSpecs, with_rays(20000));
  expect_verified(make_triangle_soup(20000, 1), kKdSpecs, with_rays(20000));
  expect_verified(make_triangle_soup(5000, 2, 6.0f), kKdSpecs, with_rays(20000));
  expect_verified(make_triangle_copies(1000), kKdSpecs, with_rays(20000));
  expect_verified(make_coplanar_scene(1000, 16, 2, 1), kKdSpecs, with_rays(20000));
  expect_verified(make_coplanar_scene(1000, 16, 0, 2), kKdSpecs, with_rays(20000));
}

TEST(KdTreeVerify, AgreesWithEmbreeOnSharedMeshes) {
  if (!test::have_shared_scenes()) GTEST_SKIP() << "no ../shared/scenes";
  for (const char* file : {"scenes/cornell_box.obj", "scenes/teapot.ply", "scenes/bunny.ply", "scenes/sponza.ply",
                           "scenes/spd/tetra_s6.obj", "scenes/spd/gears_s4.obj"})
    expect_verified(load_scene(test::shared_dir() + "/" + file), kKdSpecs, with_rays(8192));
}

}  // namespace
}  // namespace raylab
