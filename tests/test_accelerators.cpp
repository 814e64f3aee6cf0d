// Every registered accelerator against brute force and Embree: the same hits,
// ids and distances on random soups and the Cornell box; occlusion consistent
// with closest hit; invalid rays and empty scenes handled. New accelerators
// are covered automatically through the registry.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>

#include "accel/registry.h"
#include "tracer/ray_sets.h"
#include "checks/classify.h"
#include "checks/verify.h"
#include "scenes/procedural.h"
#include "scenes/scene_registry.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

// Every spec the registry asks to cover, except the reference (Embree, tested
// below), brute force itself (the ground truth here) and Moller-Trumbore
// variants (a different test may pick the other triangle at a shared edge).
std::vector<std::string> tested_accelerators() {
  std::vector<std::string> specs;
  for (const auto& spec : coverage_specs()) {
    const std::string name = Spec::parse(spec).name;
    if (accelerator_info(name).caps.reference || name == "brute" || spec.find("tri=mt") != std::string::npos) continue;
    specs.push_back(spec);
  }
  return specs;
}

std::string test_name(const std::string& spec) {
  std::string s = spec;
  for (char& c : s)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return s;
}

class EveryAccelerator : public ::testing::TestWithParam<std::string> {};

// Compares closest hits with brute force: same hit/miss, and the same
// triangle or (for coplanar/shared-edge ties) exactly the same distance.
// Both use the same watertight test on the same vertices, so distances of
// the same triangle are bit-identical.
void expect_same_as_brute(const Scene& scene, const std::string& spec, const std::vector<Ray>& rays,
                          bool expect_hits = true) {
  auto accel = make_accelerator(spec);
  auto brute = make_accelerator("brute");
  accel->build(scene.mesh);
  brute->build(scene.mesh);
  std::vector<Hit> a(rays.size()), b(rays.size());
  std::vector<uint8_t> occ(rays.size());
  accel->intersect(rays, a);
  brute->intersect(rays, b);
  accel->occluded(rays, occ);
  size_t hits = 0, bad = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    hits += b[i].valid();
    const bool same = a[i].valid() == b[i].valid() && (!a[i].valid() || a[i].prim == b[i].prim || a[i].t == b[i].t);
    if (!same && bad++ < 5)
      ADD_FAILURE() << spec << " ray " << i << ": got prim " << a[i].prim << " t " << a[i].t << ", brute prim "
                    << b[i].prim << " t " << b[i].t;
    if (a[i].valid() && a[i].prim == b[i].prim) {
      EXPECT_EQ(a[i].u, b[i].u);
      EXPECT_EQ(a[i].v, b[i].v);
    }
    EXPECT_EQ(static_cast<bool>(occ[i]), b[i].valid()) << spec << " occlusion, ray " << i;
  }
  EXPECT_EQ(bad, 0u) << spec << " on " << scene.name;
  if (expect_hits) {
    EXPECT_GT(hits, rays.size() / 20) << "ray set too easy: few hits on " << scene.name;
  }
}

TEST_P(EveryAccelerator, AgreesWithBruteForceOnSoups) {
  for (size_t n : {1u, 7u, 300u, 5000u}) {
    const Scene s = make_triangle_soup(n, 11 + n, n < 10 ? 20.0f : 1.0f);
    auto ref = make_accelerator("brute");
    ref->build(s.mesh);
    RaySetOptions o;
    o.jittered_primary = true;
    o.primary_count = 3000;
    o.random_count = 3000;
    for (const auto& set : make_ray_sets(s, {"primary", "random"}, *ref, o))
      expect_same_as_brute(s, GetParam(), set.rays, n >= 300);
  }
}

TEST_P(EveryAccelerator, AgreesWithBruteForceOnCornellBox) {
  const Scene s = make_cornell_box();
  auto ref = make_accelerator("brute");
  ref->build(s.mesh);
  RaySetOptions o;
  o.width = 64;
  o.height = 64;
  o.random_count = 5000;
  for (const auto& set : make_ray_sets(s, {"primary", "random", "diffuse"}, *ref, o))
    expect_same_as_brute(s, GetParam(), set.rays);
}

TEST_P(EveryAccelerator, AgreesWithEmbreeAfterArbitration) {
  // Brute force is O(N) per ray: it gets a smaller soup.
  const char* soup = GetParam() == "brute" ? "soup:n=2000,seed=3" : "soup:n=20000,seed=3";
  for (const char* scene : {soup, "cornell", "sphere:segments=64,rings=32"}) {
    VerifyOptions vo;
    vo.rays = 20000;
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

TEST_P(EveryAccelerator, InvalidRaysMiss) {
  const Scene s = make_triangle_soup(100, 5);
  auto accel = make_accelerator(GetParam());
  accel->build(s.mesh);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const std::vector<Ray> rays = {
      Ray(Vec3f(nan, 0.5f, 0.5f), Vec3f(1, 0, 0)),      Ray(Vec3f(0.5f, 0.5f, -1), Vec3f(0, 0, 0)),
      Ray(Vec3f(0.5f, 0.5f, -1), Vec3f(0, nan, 1)),     Ray(Vec3f(inf, 0.5f, 0.5f), Vec3f(-1, 0, 0)),
      Ray(Vec3f(0.5f, 0.5f, -1), Vec3f(0, 0, 1), 2, 1),  // tmin > tmax
      Ray(Vec3f(0.5f, 0.5f, -1), Vec3f(0, 0, 1), nan, 5),
  };
  std::vector<Hit> hits(rays.size());
  std::vector<uint8_t> occ(rays.size(), 7);
  accel->intersect(rays, hits);
  accel->occluded(rays, occ);
  for (size_t i = 0; i < rays.size(); ++i) {
    EXPECT_FALSE(hits[i].valid()) << GetParam() << " ray " << i;
    EXPECT_EQ(occ[i], 0) << GetParam() << " ray " << i;
  }
}

TEST_P(EveryAccelerator, EmptyAndSingleTriangleScenes) {
  TriangleMesh empty;
  auto a = make_accelerator(GetParam());
  a->build(empty);
  EXPECT_FALSE(a->intersect1(Ray(Vec3f::Zero(), Vec3f(0, 0, 1))).valid());
  EXPECT_FALSE(a->occluded1(Ray(Vec3f::Zero(), Vec3f(0, 0, 1))));

  TriangleMesh one;
  one.vertices = {Vec3f(0, 0, 5), Vec3f(1, 0, 5), Vec3f(0, 1, 5)};
  one.triangles = {{0, 1, 2}};
  auto b = make_accelerator(GetParam());
  b->build(one);
  const Hit h = b->intersect1(Ray(Vec3f(0.2f, 0.2f, 0), Vec3f(0, 0, 1)));
  ASSERT_TRUE(h.valid());
  EXPECT_EQ(h.prim, 0u);
  EXPECT_FLOAT_EQ(h.t, 5.0f);
  EXPECT_FALSE(b->intersect1(Ray(Vec3f(0.2f, 0.2f, 0), Vec3f(0, 0, 1), 0, 4.9f)).valid());
  EXPECT_TRUE(b->occluded1(Ray(Vec3f(0.2f, 0.2f, 0), Vec3f(0, 0, 1), 0, 5.1f)));
  EXPECT_FALSE(b->intersect1(Ray(Vec3f(0.2f, 0.2f, 0), Vec3f(0, 0, -1))).valid());
}

TEST_P(EveryAccelerator, RejectsInvalidMesh) {
  TriangleMesh bad;
  bad.vertices = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)};
  bad.triangles = {{0, 1, 3}};
  EXPECT_THROW(make_accelerator(GetParam())->build(bad), MeshError);
  bad.triangles = {{0, 1, 2}};
  bad.vertices[1].y() = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(make_accelerator(GetParam())->build(bad), MeshError);
}

TEST_P(EveryAccelerator, CountersAreFilledByTheInstrumentedKernel) {
  const Scene s = make_triangle_soup(2000, 9);
  auto a = make_accelerator(GetParam());
  a->build(s.mesh);
  auto ref = make_accelerator("brute");
  ref->build(s.mesh);
  RaySetOptions o;
  o.width = 32;
  o.height = 32;
  const RaySet set = make_ray_sets(s, {"primary"}, *ref, o)[0];
  std::vector<Hit> plain(set.rays.size()), counted(set.rays.size());
  TraversalStats stats;
  a->intersect(set.rays, plain);
  a->intersect(set.rays, counted, &stats);
  for (size_t i = 0; i < plain.size(); ++i) ASSERT_EQ(plain[i].prim, counted[i].prim);
  EXPECT_EQ(stats.rays, set.rays.size());
  EXPECT_GT(stats.triangle_tests, 0u);
}

INSTANTIATE_TEST_SUITE_P(Registry, EveryAccelerator, ::testing::ValuesIn(tested_accelerators()),
                         [](const auto& info) { return test_name(info.param); });

TEST(Accelerator, BuildsOnceAndTracesNothingBefore) {
  const Scene s = make_triangle_soup(100, 4);
  for (const auto& spec : coverage_specs()) {
    auto a = make_accelerator(spec);
    // Before build(): misses, or an exception for structures that say so; never a crash.
    const Ray r(Vec3f(0, 0, -10), Vec3f(0, 0, 1));
    try {
      EXPECT_FALSE(a->intersect1(r).valid()) << spec;
    } catch (const std::exception&) {
    }
    a->build(s.mesh);
    EXPECT_THROW(a->build(s.mesh), std::logic_error) << spec;
  }
}

TEST(Registry, EveryStatisticIsDeclared) {
  const Scene s = make_triangle_soup(500, 6);
  for (const auto& spec : coverage_specs()) {
    const AcceleratorInfo& info = accelerator_info(Spec::parse(spec).name);
    const BuildStats st = make_accelerator(spec)->build(s.mesh);
    for (const auto& [key, value] : st.extra) {
      bool declared = false;
      for (const auto& d : info.stats) declared |= d.key == key;
      EXPECT_TRUE(declared) << spec << " reports '" << key << "' without declaring it";
    }
    for (const auto& d : info.stats) EXPECT_FALSE(d.help.empty()) << spec << " " << d.key;
  }
}

TEST(Registry, ReservedUnknownNameIsNeverRegistered) {
  for (const auto& info : accelerator_registry()) EXPECT_NE(info.name, kReservedUnknownAccelerator);
  EXPECT_THROW(make_accelerator(kReservedUnknownAccelerator), SpecError);
}

TEST(Registry, CoverageSpecsAllBuildAndNameTheirStructure) {
  const std::vector<std::string> specs = coverage_specs();
  for (const auto& info : accelerator_registry()) {
    EXPECT_NE(std::find(specs.begin(), specs.end(), info.name), specs.end()) << info.name;
    for (const auto& c : info.cover) EXPECT_EQ(Spec::parse(c).name, info.name) << c;
    if (!info.caps.mt_variant.empty()) {
      EXPECT_NO_THROW(make_accelerator(info.name + ":" + info.caps.mt_variant));
    }
    if (!info.caps.robust_variant.empty()) {
      EXPECT_NO_THROW(make_accelerator(info.name + ":" + info.caps.robust_variant));
    }
  }
}

TEST(Embree, AgreesWithBruteForceOnSoup) {
  const Scene s = make_triangle_soup(3000, 2);
  auto e = make_accelerator("embree:robust=1");
  const BuildStats st = e->build(s.mesh);
  auto b = make_accelerator("brute");
  b->build(s.mesh);
  RaySetOptions o;
  o.random_count = 5000;
  const RaySet set = make_ray_sets(s, {"random"}, *b, o)[0];
  size_t disagree = 0;
  for (const Ray& r : set.rays) {
    const Hit x = e->intersect1(r), y = b->intersect1(r);
    disagree += screen_closest(x, y) == Screen::Disagree;
  }
  EXPECT_LE(disagree, 2u);
  EXPECT_GT(st.bytes, 3000u * 10);
}

}  // namespace
}  // namespace raylab

namespace raylab {
namespace {

// Issue 17: a structure's scalar variant (caps.scalar_variant, "simd=0")
// runs the same algorithm and the same triangle test without SIMD kernels,
// so it must give exactly the same hits (distance, barycentrics, triangle),
// the same occlusion answers and the same counted work as the default.
TEST(Registry, ScalarVariantGivesIdenticalHits) {
  const Scene soup = make_triangle_soup(3000, 17);
  const TriangleMesh sphere = make_uv_sphere(48, 24);
  size_t structures = 0;
  for (const auto& info : accelerator_registry()) {
    if (info.caps.scalar_variant.empty()) continue;
    ++structures;
    for (const TriangleMesh* mesh : {&soup.mesh, &sphere}) {
      // Origins in the mesh's box (inside the sphere, among the soup), random directions.
      std::vector<Ray> rays;
      Pcg32 rng(5, 17);
      const Aabb box = mesh->bounds();
      for (int i = 0; i < 3000; ++i) {
        const Vec3f u(rng.uniform(), rng.uniform(), rng.uniform());
        rays.emplace_back(Vec3f(box.lo + u.cwiseProduct(box.hi - box.lo)), test::random_direction(rng));
      }
      auto simd = make_accelerator(info.name);
      auto scalar = make_accelerator(info.name + ":" + info.caps.scalar_variant);
      simd->build(*mesh);
      scalar->build(*mesh);
      std::vector<Hit> a(rays.size()), b(rays.size());
      std::vector<uint8_t> oa(rays.size()), ob(rays.size());
      TraversalStats sa, sb;
      simd->intersect(rays, a, &sa);
      scalar->intersect(rays, b, &sb);
      simd->occluded(rays, oa);
      scalar->occluded(rays, ob);
      size_t hits = 0;
      for (size_t i = 0; i < rays.size(); ++i) {
        hits += a[i].valid();
        ASSERT_EQ(a[i].prim, b[i].prim) << info.name << " ray " << i;
        ASSERT_EQ(a[i].t, b[i].t) << info.name << " ray " << i;
        ASSERT_EQ(a[i].u, b[i].u) << info.name << " ray " << i;
        ASSERT_EQ(a[i].v, b[i].v) << info.name << " ray " << i;
        ASSERT_EQ(oa[i], ob[i]) << info.name << " ray " << i;
      }
      EXPECT_GT(hits, rays.size() / 10) << info.name;
      EXPECT_EQ(sa.nodes_visited, sb.nodes_visited) << info.name;
      EXPECT_EQ(sa.triangle_tests, sb.triangle_tests) << info.name;
    }
  }
  EXPECT_GT(structures, 0u);
}

}  // namespace
}  // namespace raylab
