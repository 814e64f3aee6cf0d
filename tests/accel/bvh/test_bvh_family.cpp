// The `bvh` registry entry as a whole: every builder x layout x option
// combination against brute force (hits, distances bit for bit, occlusion)
// with the counting kernel, its statistics and ISA, bad parameters, the
// Moller-Trumbore blocks, scalar variants, coincident triangles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "accel/bvh/bvh_accel.h"
#include "accel/registry.h"
#include "base/pcg.h"
#include "tests/accel/bvh/bvh_test_util.h"
#include "tests/accel_test_util.h"
#include "tests/brute_agreement.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

using test::build_with;
using test::check_binary_tree;
using test::ReferenceScene;
using test::reference_scenes;

std::vector<std::string> family_specs() {
  std::vector<std::string> specs;
  for (const char* b : {"binned", "sweep", "sbvh", "lbvh"})
    for (const char* l : {"bvh2", "bvh4", "bvh8"}) specs.push_back(fmt::format("bvh:builder={},layout={}", b, l));
  for (const char* extra :
       {"bvh:opt=reinsert,layout=bvh2", "bvh:opt=reinsert,layout=bvh8", "bvh:opt=reinsert,builder=sbvh,layout=bvh4",
        "bvh:leaf=8", "bvh:leaf=48", "bvh:leaf=4,opt=reinsert", "bvh:builder=sbvh,sbudget=2",
        "bvh:builder=sbvh,smin=64", "bvh:layout=bvh2,leaf=1", "bvh:ct=4,ci=0.5", "bvh:bins=4",
        "bvh:layout=bvh16", "bvh:layout=bvh16,opt=reinsert", "bvh:layout=bvh16,builder=sbvh,leaf=4",
        "bvh:layout=bvh16,builder=lbvh", "bvh:layout=bvh8,simd=0", "bvh:layout=bvh16,simd=0",
        "bvh:preset=fast", "bvh:preset=quality", "bvh:preset=sbvh", "bvh:preset=sbvh,layout=bvh16"})
    specs.push_back(extra);
  return specs;
}

class BvhFamily : public ::testing::TestWithParam<std::string> {};

TEST_P(BvhFamily, AgreesWithBruteForce) {
  for (const ReferenceScene& ref : reference_scenes()) {
    auto accel = make_accelerator(GetParam());
    const BuildStats st = accel->build(ref.scene.mesh);
    EXPECT_TRUE(st.nodes > 0 || st.leaves == 1) << "a single leaf needs no node";
    EXPECT_GT(st.leaves, 0u);
    EXPECT_GT(st.bytes, 0u);
    EXPECT_TRUE(std::isfinite(st.sah_cost) && st.sah_cost > 0.0) << GetParam();
    size_t hits = 0;
    for (size_t s = 0; s < ref.sets.size(); ++s) {
      // Overlapping coplanar triangles (the size-6 soup, clamped to the unit
      // cube's faces) tie up to rounding of the coordinates: 1e-6.
      const std::string what = GetParam() + " " + ref.scene.name + " " + ref.sets[s].name;
      const test::Disagreement d = test::compare_with_brute(*accel, ref.brute[s], ref.sets[s].rays, {.tie_rel = 1e-6f});
      EXPECT_EQ(d.total(), 0u) << what << ":\n" << d.examples;
      hits += d.reference_hits;
    }
    EXPECT_GT(hits, 300u) << "the ray sets must hit something on " << ref.scene.name;
  }
}

TEST_P(BvhFamily, InstrumentedKernelCountsAndAgrees) {
  const ReferenceScene& ref = reference_scenes()[0];
  auto accel = make_accelerator(GetParam());
  accel->build(ref.scene.mesh);
  const auto& rays = ref.sets[1].rays;
  std::vector<Hit> plain(rays.size()), counted(rays.size());
  std::vector<uint8_t> occ_plain(rays.size()), occ_counted(rays.size());
  TraversalStats st, st_occ;
  accel->intersect(rays, plain);
  accel->intersect(rays, counted, &st);
  accel->occluded(rays, occ_plain);
  accel->occluded(rays, occ_counted, &st_occ);
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_EQ(plain[i].prim, counted[i].prim);
    ASSERT_EQ(occ_plain[i], occ_counted[i]);
  }
  EXPECT_EQ(st.rays, rays.size());
  EXPECT_GT(st.nodes_visited, rays.size());
  EXPECT_GT(st.triangle_tests, 0u);
  // Any hit stops early: never more work than closest hit on the same rays.
  EXPECT_LE(st_occ.triangle_tests, st.triangle_tests);
}

INSTANTIATE_TEST_SUITE_P(Combinations, BvhFamily, ::testing::ValuesIn(family_specs()), [](const auto& info) {
  std::string n = info.param.substr(4);
  for (char& c : n)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return n;
});

TEST(BvhFamily, ReportsSimdIsaAndStatistics) {
  const test::NamedMesh s = test::soup(1000, 3);
  for (const char* spec : {"bvh", "bvh:layout=bvh4", "bvh:layout=bvh2"}) {
    auto a = make_accelerator(spec);
    const BuildStats st = a->build(s.mesh);
    EXPECT_GT(st.build_ms, 0.0);
    EXPECT_GT(st.max_depth, 0);
    EXPECT_GT(st.avg_depth, 0.0);
    EXPECT_TRUE(st.extra.count("sah_tree")) << spec;
    EXPECT_TRUE(st.extra.count("ms_tree")) << spec;
    if (std::string(spec) != "bvh:layout=bvh2") {
      ASSERT_TRUE(st.extra.count("simd_bits")) << spec;
      EXPECT_GE(st.extra.at("simd_bits"), 32.0);
    }
  }
  EXPECT_FALSE(bvh_kernel_isa().empty());
  EXPECT_NE(bvh_kernel_isa(), "unknown");
}

TEST(BvhFamily, RejectsBadParameters) {
  for (const char* spec : {"bvh:leaf=0", "bvh:leaf=-1", "bvh:leaf=many", "bvh:builder=octree", "bvh:layout=bvh3",
                           "bvh:tri=mt,simd=0", "bvh:tri=mt,packet=16", "bvh:bins=1", "bvh:sbudget=9", "bvh:ct=0",
                           "bvh:opt=anneal", "bvh:leaf=500", "bvh:leaf=121", "bvh:smin=-2", "bvh:nodes=3",
                           "bvh:layout=bvh32", "bvh:preset=best", "bvh:preset=", "bvh:bound=sphere,layout=bvh8"})
    EXPECT_THROW(make_accelerator(spec), SpecError) << spec;
  EXPECT_NO_THROW(make_accelerator("bvh:layout=bvh2,tri=mt"));
  EXPECT_NO_THROW(make_accelerator("bvh:tri=mt"));
  EXPECT_NO_THROW(make_accelerator("bvh:tri=mt,layout=bvh4"));
  EXPECT_NO_THROW(make_accelerator("bvh:leaf=auto"));
  EXPECT_NO_THROW(make_accelerator("bvh:leaf=120"));
  EXPECT_NO_THROW(make_accelerator("bvh:layout=bvh2,leaf=255"));
}

// tri=mt (the non-watertight option, measuring what watertightness costs) tests the
// wide layouts' blocks with the vectorised Moller-Trumbore test, which
// computes what the scalar intersect_moller_trumbore computes lane by lane
// (its pre-division range test is conservative): the same closest hits as
// brute force with that test, bit for bit, and the same occlusion answers.
TEST(BvhFamily, MollerTrumboreBlocksMatchBruteForceWithTheSameTest) {
  std::vector<test::NamedMesh> scenes;
  scenes.push_back(test::soup(2000, 53));
  scenes.push_back(test::soup(400, 5, 6.0f));  // long, heavily overlapping triangles
  for (const test::NamedMesh& s : scenes) {
    std::vector<Ray> rays = test::mesh_test_rays(s.mesh, 3000, 61);
    // Rays through vertices and edge midpoints, where the test's rounding decides.
    for (size_t t = 0; t < std::min<size_t>(s.mesh.num_triangles(), 300); ++t) {
      const Vec3f target = t % 2 ? s.mesh.vertex(t, 0) : 0.5f * (s.mesh.vertex(t, 1) + s.mesh.vertex(t, 2));
      const Vec3f org = target + Vec3f(0.3f, 2.0f, -0.7f);
      rays.push_back(Ray(org, (target - org).normalized()));
    }
    auto brute = make_accelerator("brute:tri=mt");
    brute->build(s.mesh);
    for (const char* spec : {"bvh:tri=mt", "bvh:tri=mt,layout=bvh4", "bvh:tri=mt,layout=bvh16",
                             "bvh:tri=mt,opt=reinsert"}) {
      auto accel = make_accelerator(spec);
      accel->build(s.mesh);
      size_t bad = 0, bad_occ = 0, hits = 0;
      for (const Ray& r : rays) {
        const Hit a = accel->intersect1(r), b = brute->intersect1(r);
        const bool differs = a.valid() != b.valid() ||
                             (a.valid() && (a.t != b.t || a.u != b.u || a.v != b.v || a.prim != b.prim));
        if (differs && bad == 0)
          ADD_FAILURE() << fmt::format("{}: first difference: t {} / {}, u {} / {}, v {} / {}, prim {} / {}", spec,
                                       a.t, b.t, a.u, b.u, a.v, b.v, a.prim, b.prim);
        bad += differs;
        bad_occ += accel->occluded1(r) != b.valid();
        hits += b.valid();
      }
      EXPECT_GT(hits, rays.size() / 4) << spec;
      EXPECT_EQ(bad, 0u) << spec << " " << s.name;
      EXPECT_EQ(bad_occ, 0u) << spec << " " << s.name;
    }
  }
}

TEST(BvhFamily, ScalarTestsGiveIdenticalHitsAndCounts) {
  // simd=0 walks the same wide tree with scalar box and triangle tests: the
  // same hits bit for bit, the same occlusion and the same counted work, for
  // both wide layouts and for the rays that take the exact box test
  // (axis-parallel, tmin < 0) as well as the FMA one. The registry-wide test
  // (Registry.ScalarVariantGivesIdenticalHits) covers the default layout.
  const test::NamedMesh s = test::soup(2500, 29);
  std::vector<Ray> rays = test::camera_rays(s.mesh, 40, 30);
  Pcg32 rng(3, 11);
  const Aabb box = s.mesh.bounds();
  for (int i = 0; i < 1500; ++i) {
    const Vec3f u(rng.uniform(), rng.uniform(), rng.uniform());
    rays.emplace_back(Vec3f(box.lo + u.cwiseProduct(box.hi - box.lo)), test::random_direction(rng));
  }
  for (size_t i = 3; i < rays.size(); i += 37) rays[i].dir.y() = 0.0f;  // axis-parallel component
  for (size_t i = 7; i < rays.size(); i += 41) rays[i].tmin = -1.0f;     // tmin < 0
  for (const char* layout : {"bvh8", "bvh4", "bvh16"}) {
    auto simd = make_accelerator(fmt::format("bvh:layout={}", layout));
    auto scalar = make_accelerator(fmt::format("bvh:layout={},simd=0", layout));
    simd->build(s.mesh);
    scalar->build(s.mesh);
    std::vector<Hit> a(rays.size()), b(rays.size());
    std::vector<uint8_t> oa(rays.size()), ob(rays.size());
    TraversalStats sa, sb, soa, sob;
    simd->intersect(rays, a, &sa);
    scalar->intersect(rays, b, &sb);
    simd->occluded(rays, oa, &soa);
    scalar->occluded(rays, ob, &sob);
    size_t hits = 0, bad = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      hits += a[i].valid();
      bad += std::memcmp(&a[i], &b[i], sizeof(Hit)) != 0 || oa[i] != ob[i];
    }
    EXPECT_EQ(bad, 0u) << layout;
    EXPECT_GT(hits, rays.size() / 4) << layout;
    EXPECT_EQ(sa.nodes_visited, sb.nodes_visited) << layout;
    EXPECT_EQ(sa.triangle_tests, sb.triangle_tests) << layout;
    EXPECT_EQ(soa.nodes_visited, sob.nodes_visited) << layout;
    EXPECT_EQ(soa.triangle_tests, sob.triangle_tests) << layout;
  }
  EXPECT_THROW(make_accelerator("bvh:simd=0,packet=16"), SpecError);
}

TEST(BvhFamily, CoincidentTrianglesEveryBuilder) {
  // 600 copies of one triangle plus 600 of another: identical centroids
  // force the median fallbacks; every copy must stay reachable.
  TriangleMesh m;
  m.vertices = {Vec3f(0, 0, 1), Vec3f(1, 0, 1), Vec3f(0, 1, 1), Vec3f(0, 0, 2), Vec3f(1, 0, 2), Vec3f(0, 1, 2)};
  for (int i = 0; i < 600; ++i) m.triangles.push_back({0, 1, 2}), m.triangles.push_back({3, 4, 5});
  for (const char* b : {"binned", "sweep", "sbvh", "lbvh"}) {
    for (const char* l : {"bvh2", "bvh8"}) {
      const std::string spec = fmt::format("bvh:builder={},layout={}", b, l);
      auto a = make_accelerator(spec);
      const BuildStats st = a->build(m);
      EXPECT_LT(st.max_depth, 64) << spec;
      const Hit h = a->intersect1(Ray(Vec3f(0.2f, 0.2f, 0), Vec3f(0, 0, 1)));
      ASSERT_TRUE(h.valid()) << spec;
      EXPECT_EQ(h.t, 1.0f) << spec;
      EXPECT_EQ(m.triangles[h.prim][0], 0u) << spec;
      EXPECT_EQ(h.prim, 0u) << spec << ": exact ties go to the lowest primitive id (HitRecorder)";
      EXPECT_TRUE(a->occluded1(Ray(Vec3f(0.2f, 0.2f, 3), Vec3f(0, 0, -1)))) << spec;
    }
    const BinaryBvh t = build_with(b, m);
    check_binary_tree(t, m, std::string(b) == "sbvh");
  }
}

}  // namespace
}  // namespace raylab
