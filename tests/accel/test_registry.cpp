// Every registered accelerator against brute force: the same hits, ids and
// distances on random soups and the Cornell box; occlusion consistent with
// closest hit; invalid rays and empty scenes handled. New accelerators are
// covered automatically through the registry. (Against Embree, through the
// checks layer's oracle: tests/test_structures_verify.cpp.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <utility>

#include "accel/registry.h"
#include "base/mesh_shapes.h"
#include "base/pcg.h"
#include "tests/accel_test_util.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

class EveryAccelerator : public ::testing::TestWithParam<std::string> {};

// Compares closest hits with brute force: same hit/miss, and the same
// triangle or (for coplanar/shared-edge ties) exactly the same distance.
// Both use the same watertight test on the same vertices, so distances of
// the same triangle are bit-identical.
void expect_same_as_brute(const test::NamedMesh& scene, const std::string& spec, const std::vector<Ray>& rays,
                          bool expect_hits = true) {
  auto accel = make_accelerator(spec);
  accel->build(scene.mesh);
  const test::Disagreement d =
      test::compare_with_brute(*accel, test::brute_reference(scene.mesh, rays), rays, spec + " on " + scene.name);
  EXPECT_EQ(d.closest + d.barycentric + d.occlusion, 0u) << spec << " on " << scene.name;
  if (expect_hits) {
    EXPECT_GT(d.reference_hits, rays.size() / 20) << "ray set too easy: few hits on " << scene.name;
  }
}

TEST_P(EveryAccelerator, AgreesWithBruteForceOnSoups) {
  for (size_t n : {1u, 7u, 300u, 5000u}) {
    const test::NamedMesh s = test::soup(n, 11 + n, n < 10 ? 20.0f : 1.0f);
    expect_same_as_brute(s, GetParam(), test::camera_rays(s.mesh, 55, 55), n >= 300);
    expect_same_as_brute(s, GetParam(), test::mesh_test_rays(s.mesh, 3000, n), n >= 300);
  }
}

TEST_P(EveryAccelerator, AgreesWithBruteForceOnCornellBox) {
  const test::NamedMesh s{"cornell", cornell_box_mesh()};
  const std::vector<Ray> primary = test::camera_rays(s.mesh, 64, 64);
  const test::BruteReference ref = test::brute_reference(s.mesh, primary);
  expect_same_as_brute(s, GetParam(), primary);
  expect_same_as_brute(s, GetParam(), test::mesh_test_rays(s.mesh, 5000, 1));
  expect_same_as_brute(s, GetParam(), test::surface_rays(s.mesh, primary, ref.hits, 2));
}

TEST_P(EveryAccelerator, InvalidRaysMiss) {
  const TriangleMesh mesh = triangle_soup_mesh(100, 5);
  auto accel = make_accelerator(GetParam());
  accel->build(mesh);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const std::vector<Ray> rays = {
      Ray(Vec3f(nan, 0.5f, 0.5f), Vec3f(1, 0, 0)),      Ray(Vec3f(0.5f, 0.5f, -1), Vec3f(0, 0, 0)),
      Ray(Vec3f(0.5f, 0.5f, -1), Vec3f(0, nan, 1)),     Ray(Vec3f(inf, 0.5f, 0.5f), Vec3f(-1, 0, 0)),
      Ray(Vec3f(0.5f, 0.5f, -1), Vec3f(0, 0, 1), 2, 1),  // tmin > tmax
      Ray(Vec3f(0.5f, 0.5f, -1), Vec3f(0, 0, 1), nan, 5),
      Ray(Vec3f(0.5f, 0.5f, -1), Vec3f(0, 0, 0x1p-149f), inf, inf),  // a segment starting at infinity
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

// Valid rays at the edges of float: direction components so small that
// their reciprocals (and the structures' margins divided by them) overflow,
// denormal tmin, distances that round to inf, huge directions. Found by
// fuzz_rays: the BSP tree's clip widened by inf - inf = NaN and its
// closest-hit walk skipped the tree while its any-hit walk did not. Every
// structure must give brute force's closest hits and an any-hit answer that
// agrees with them.
void expect_extreme_rays_agree(const std::string& spec, const std::string& what, const TriangleMesh& mesh,
                               const std::vector<Ray>& rays, size_t min_hits) {
  auto accel = make_accelerator(spec);
  accel->build(mesh);
  const test::Disagreement d =
      test::compare_with_brute(*accel, test::brute_reference(mesh, rays), rays, spec + " on " + what);
  EXPECT_EQ(d.closest + d.barycentric + d.occlusion, 0u) << spec << " on " << what;
  EXPECT_GE(d.reference_hits, min_hits) << what;
  // A hit's distance is a finite float: triangles met beyond FLT_MAX are misses (hit_recorder.h).
  std::vector<Hit> hits(rays.size());
  accel->intersect(rays, hits);
  size_t infinite = 0;
  for (const Hit& h : hits) infinite += h.valid() && !std::isfinite(h.t);
  EXPECT_EQ(infinite, 0u) << spec << " on " << what;
}

TEST_P(EveryAccelerator, ExtremeValidRaysAgreeWithBruteForce) {
  TriangleMesh mesh = cornell_box_mesh();
  for (auto& v : mesh.vertices) v *= 1.0f / 550.0f;  // the unit box, as in fuzz_rays
  mesh.append(make_uv_sphere(12, 6, Vec3f(0.5f, 0.5f, 0.5f), 0.2f));
  const float inf = std::numeric_limits<float>::infinity();
  const std::vector<Vec3f> origins = {Vec3f(0.5f, 0.5000035f, -1.0f), Vec3f(0.3f, 0.6f, 0.45f),
                                      Vec3f(-2.0f, 0.25f, 0.5f)};
  const std::vector<Vec3f> directions = {Vec3f(0, 0, 1),    Vec3f(1, 0, 0),      Vec3f(0, -1, 0),
                                         Vec3f(1, 1, 1),    Vec3f(-1, 1, 0),     Vec3f(0.3f, -0.2f, 0.9f),
                                         Vec3f(1, 1e-30f, 0), Vec3f(-0.0f, 0, 1)};
  const std::vector<float> scales = {0x1p-149f, 0x1p-148f, 0x1p-140f, 0x1p-126f, 1e-30f, 1.0f, 1e30f, 0x1p127f};
  const std::vector<std::pair<float, float>> intervals = {{0.0f, inf}, {0x1p-134f, inf}, {1e-3f, 1e30f}, {1e30f, inf}, {inf, inf}};
  std::vector<Ray> rays;
  for (const Vec3f& o : origins)
    for (const Vec3f& d : directions)
      for (float s : scales)
        for (const auto& [t0, t1] : intervals) rays.emplace_back(o, d * s, t0, t1);
  expect_extreme_rays_agree(GetParam(), "extreme rays in the unit box", mesh, rays, rays.size() / 8);
}

// Rays with one direction component below 2^-128 (its reciprocal overflows)
// that reach, at a finite distance, triangles lying beside the origin's
// coordinate on that axis: the strips stand 2^-121 to 2^-119 off the
// origin's plane, 1000 units ahead, where the ray has drifted 2^-130 * 1000
// ~ 2^-120. A slab test with 1 / d = +-inf puts such a box at t = +inf.
// One scene per pair of (main, tiny) axes; the strips are cut into 16 pieces
// along the third axis so that trees and grids subdivide them.
TEST_P(EveryAccelerator, RaysWithOverflowingReciprocalsReachBoxesBesideTheirPlane) {
  for (int main_axis = 0; main_axis < 3; ++main_axis)
    for (int tiny_axis = 0; tiny_axis < 3; ++tiny_axis) {
      if (tiny_axis == main_axis) continue;
      const int side_axis = 3 - main_axis - tiny_axis;
      auto point = [&](float m, float t, float s) {
        Vec3f p;
        p[main_axis] = m, p[tiny_axis] = t, p[side_axis] = s;
        return p;
      };
      TriangleMesh mesh;
      for (float sign : {1.0f, -1.0f})
        for (int k = 0; k < 16; ++k) {
          const float s0 = -1.0f + k / 8.0f, s1 = s0 + 1.0f / 8.0f;
          const uint32_t b = static_cast<uint32_t>(mesh.vertices.size());
          mesh.vertices.push_back(point(1000.0f, sign * 0x1p-121f, s0));
          mesh.vertices.push_back(point(1000.0f, sign * 0x1p-119f, s0));
          mesh.vertices.push_back(point(1000.0f, sign * 0x1p-119f, s1));
          mesh.vertices.push_back(point(1000.0f, sign * 0x1p-121f, s1));
          mesh.triangles.push_back({b, b + 1, b + 2});
          mesh.triangles.push_back({b, b + 2, b + 3});
        }
      std::vector<Ray> rays;
      for (float sign : {1.0f, -1.0f})
        for (int k = 0; k < 32; ++k) {
          const float side = (k - 15.5f) / 16.0f * 0.0009f;  // lands at 1000 * side in (-0.9, 0.9)
          rays.emplace_back(Vec3f::Zero(), point(1.0f, sign * 0x1p-130f, side));
          rays.emplace_back(Vec3f::Zero(), point(1.0f, sign * 0x1p-130f, side), 999.0f, 1001.0f);
        }
      expect_extreme_rays_agree(GetParam(),
                                "strips beside the origin, axes " + std::to_string(main_axis) +
                                    std::to_string(tiny_axis),
                                mesh, rays, rays.size() * 9 / 10);
    }
}

// Rays from far away (origins 2^10 to 2^112 from a unit-sized scene) aimed
// at points inside it. Found by fuzz_rays: a ray from z = -2^50 along +z,
// whose grid walk computed its cells with errors of a quarter unit and
// stopped a cell short of the back wall (dda.h, dda_line); and one from
// z = -2^104 with |dir| = 0.003, whose rebased walk still started 2^51
// units out and lost the back wall in the two-level grid.
//  - Along an axis (the other two components 0, the origin's other
//    coordinates inside the box, some just inside a wall) the watertight
//    test's shear is exact, so its hit or miss is the exact one and every
//    structure must agree with brute force; the distances round to 2^-24 of
//    the origin's distance, so another triangle within 2^-20 is a tie.
//  - Oblique rays: the float test subtracts the origin from the vertices,
//    which blurs the triangles by an ulp of the origin's distance (4 units
//    at 2^26); its answers are then not the exact ones (raylab verify's
//    oracle would judge them), and a structure that follows the exact line
//    may differ from brute force. Checked: the any-hit answer agrees with
//    the closest hit, and hits lie in [tmin, tmax].
TEST_P(EveryAccelerator, RaysFromFarAwayAgreeWithBruteForce) {
  TriangleMesh mesh = cornell_box_mesh();
  for (auto& v : mesh.vertices) v *= 1.0f / 550.0f;
  mesh.append(make_uv_sphere(12, 6, Vec3f(0.5f, 0.5f, 0.5f), 0.2f));
  const Aabb box = mesh.bounds();
  Pcg32 rng(17, 5);
  std::vector<Ray> axis_rays, oblique_rays;
  for (int e : {10, 14, 18, 22, 26, 30, 34, 38, 42, 46, 50, 64, 88, 104, 112})
    for (int i = 0; i < 40; ++i) {
      const Vec3f target = box.lo + Vec3f(rng.uniform(), rng.uniform(), rng.uniform()).cwiseProduct(box.diagonal());
      if (i % 2 == 0) {
        const int a = static_cast<int>(rng.next() % 3);
        Vec3f org = target, dir = Vec3f::Zero();
        org[a] = (i % 4 == 0 ? -1.0f : 1.0f) * std::ldexp(1.0f, e);
        dir[a] = (i % 4 == 0 ? 1.0f : -1.0f) * (i % 8 < 4 ? 1.0f : i % 16 < 8 ? 1.00675f : 0x1.7fp-9f);
        if (i % 6 == 0) org[(a + 1) % 3] = box.lo[(a + 1) % 3] + 0x1p-138f;  // the crash: just inside a wall
        axis_rays.emplace_back(org, dir);
      } else {
        const Vec3f org = target + std::ldexp(1.0f, e) * test::random_direction(rng);
        oblique_rays.emplace_back(org, (target - org).normalized());
        oblique_rays.emplace_back(org, target - org);  // unnormalised: t near 1
      }
    }
  auto accel = make_accelerator(GetParam());
  accel->build(mesh);
  const test::Disagreement d = test::compare_with_brute(*accel, test::brute_reference(mesh, axis_rays), axis_rays,
                                                        GetParam() + " on axis rays from far away", 0x1p-20f);
  EXPECT_EQ(d.closest + d.barycentric + d.occlusion, 0u) << GetParam();
  EXPECT_GT(d.reference_hits, axis_rays.size() * 9 / 10);
  std::vector<Hit> hits(oblique_rays.size());
  std::vector<uint8_t> occ(oblique_rays.size());
  accel->intersect(oblique_rays, hits);
  accel->occluded(oblique_rays, occ);
  size_t inconsistent = 0, hit_count = 0;
  for (size_t i = 0; i < hits.size(); ++i) {
    inconsistent += (occ[i] != 0) != hits[i].valid() ||
                    (hits[i].valid() && !(hits[i].t >= oblique_rays[i].tmin && hits[i].t <= oblique_rays[i].tmax));
    hit_count += hits[i].valid();
  }
  EXPECT_EQ(inconsistent, 0u) << GetParam();
  EXPECT_GT(hit_count, oblique_rays.size() / 4) << GetParam();
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
  const TriangleMesh mesh = triangle_soup_mesh(2000, 9);
  auto a = make_accelerator(GetParam());
  a->build(mesh);
  const std::vector<Ray> rays = test::camera_rays(mesh, 32, 32);
  std::vector<Hit> plain(rays.size()), counted(rays.size());
  TraversalStats stats;
  a->intersect(rays, plain);
  a->intersect(rays, counted, &stats);
  for (size_t i = 0; i < plain.size(); ++i) ASSERT_EQ(plain[i].prim, counted[i].prim);
  EXPECT_EQ(stats.rays, rays.size());
  EXPECT_GT(stats.triangle_tests, 0u);
}

INSTANTIATE_TEST_SUITE_P(Registry, EveryAccelerator, ::testing::ValuesIn(test::specs_checked_against_brute()),
                         [](const auto& info) { return test::gtest_name(info.param); });

TEST(Accelerator, BuildsOnceAndTracesNothingBefore) {
  const TriangleMesh mesh = triangle_soup_mesh(100, 4);
  for (const auto& spec : coverage_specs()) {
    auto a = make_accelerator(spec);
    // Before build(): misses, or an exception for structures that say so; never a crash.
    const Ray r(Vec3f(0, 0, -10), Vec3f(0, 0, 1));
    try {
      EXPECT_FALSE(a->intersect1(r).valid()) << spec;
    } catch (const std::exception&) {
    }
    a->build(mesh);
    EXPECT_THROW(a->build(mesh), std::logic_error) << spec;
  }
}

TEST(Registry, EveryStatisticIsDeclared) {
  const TriangleMesh mesh = triangle_soup_mesh(500, 6);
  for (const auto& spec : coverage_specs()) {
    const AcceleratorInfo& info = accelerator_info(Spec::parse(spec).name);
    const BuildStats st = make_accelerator(spec)->build(mesh);
    for (const auto& [key, value] : st.extra) {
      bool declared = false;
      for (const auto& d : info.stats) declared |= d.key == key;
      EXPECT_TRUE(declared) << spec << " reports '" << key << "' without declaring it";
    }
    for (const auto& d : info.stats) EXPECT_FALSE(d.help.empty()) << spec << " " << d.key;
  }
}

TEST(Registry, EveryStructureDeclaresItsBuildMemory) {
  // bench's memory estimate has no list of its own: each registry line
  // declares its peak bytes per triangle (accel/registry.h).
  for (const auto& info : accelerator_registry()) {
    EXPECT_GT(info.build_peak_bytes_per_triangle, 0.0) << info.name;
    EXPECT_LT(info.build_peak_bytes_per_triangle, 10'000.0) << info.name;
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

}  // namespace
}  // namespace raylab

namespace raylab {
namespace {

// A structure's scalar variant (caps.scalar_variant, "simd=0")
// runs the same algorithm and the same triangle test without SIMD kernels,
// so it must give exactly the same hits (distance, barycentrics, triangle),
// the same occlusion answers and the same counted work as the default.
TEST(Registry, ScalarVariantGivesIdenticalHits) {
  const test::NamedMesh soup = test::soup(3000, 17);
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
