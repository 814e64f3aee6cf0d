// The culled oracle (checks/oracle_index.h) against the loop over every
// triangle (checks/oracle.h): the same answer field by field on rays made to
// hit the bound's corner cases, and far fewer triangles tested.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "checks/oracle.h"
#include "checks/oracle_index.h"
#include "checks/stress.h"
#include "scenes/procedural.h"
#include "scenes/scene_registry.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

uint64_t bits(double x) {
  uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

// Rays over `mesh` that exercise the oracle's corner cases: random rays,
// rays aimed at vertices and edges, rays lying in (or within a small angle
// of) a triangle's plane, rays whose tmin or tmax is the distance to a
// triangle, finite and infinite tmax, negative tmin, origins far outside.
std::vector<Ray> corner_case_rays(const TriangleMesh& mesh, size_t count, uint64_t seed) {
  Pcg32 rng(seed, 3);
  const Aabb b = mesh.bounds();
  const Vec3f extent = b.hi - b.lo;
  const float size = std::max(extent.maxCoeff(), 1e-3f);
  const Vec3f center = 0.5f * (b.lo + b.hi);
  auto inside_point = [&](float grow) {
    Vec3f p;
    for (int a = 0; a < 3; ++a) p[a] = center[a] + (rng.uniform() - 0.5f) * grow * std::max(extent[a], 1e-3f);
    return p;
  };
  auto random_tri = [&] { return static_cast<size_t>(rng.next() % mesh.num_triangles()); };
  std::vector<Ray> rays;
  if (mesh.num_triangles() == 0) return rays;
  rays.reserve(count);
  while (rays.size() < count) {
    const size_t kind = rays.size() % 9;
    Ray r;
    const size_t tri = random_tri();
    const Vec3f p0 = mesh.vertex(tri, 0), p1 = mesh.vertex(tri, 1), p2 = mesh.vertex(tri, 2);
    const Vec3f e1 = p1 - p0, e2 = p2 - p0;
    switch (kind) {
      case 0:  // random
        r = Ray(inside_point(1.5f), test::random_direction(rng));
        break;
      case 1: {  // at a vertex
        const Vec3f o = inside_point(3.0f);
        r = Ray(o, mesh.vertex(tri, static_cast<int>(rng.next() % 3)) - o);
        break;
      }
      case 2: {  // at a point of an edge
        const Vec3f o = inside_point(3.0f);
        const int c = static_cast<int>(rng.next() % 3);
        const Vec3f target = mesh.vertex(tri, c) + rng.uniform() * (mesh.vertex(tri, (c + 1) % 3) - mesh.vertex(tri, c));
        r = Ray(o, target - o);
        break;
      }
      case 3: {  // in the triangle's plane
        const Vec3f o = p0 + (rng.uniform() * 3 - 1) * e1 + (rng.uniform() * 3 - 1) * e2;
        r = Ray(o, (rng.uniform() - 0.5f) * e1 + (rng.uniform() - 0.5f) * e2);
        break;
      }
      case 4: {  // a small angle off the triangle's plane, from near or far
        const Vec3f n = e1.cross(e2).normalized();
        const float far = rng.uniform() < 0.5f ? 1.0f : 30.0f;
        const Vec3f in_plane = ((rng.uniform() - 0.5f) * e1 + (rng.uniform() - 0.5f) * e2).normalized();
        const Vec3f o = p0 + far * size * (rng.uniform() - 0.5f) * in_plane + 1e-3f * size * (rng.uniform() - 0.5f) * n;
        const float angle = std::pow(10.0f, -1.0f - 6.0f * rng.uniform());
        r = Ray(o, in_plane + angle * (rng.uniform() < 0.5f ? n : Vec3f(-n)));
        break;
      }
      case 5: {  // tmax or tmin at a triangle's distance
        const Vec3f o = inside_point(2.0f);
        const Vec3f target = p0 + 0.3f * e1 + 0.3f * e2;
        r = Ray(o, target - o);
        const OracleTriangle t = oracle_triangle(mesh, r, static_cast<uint32_t>(tri));
        const float at = static_cast<float>(t.t);
        if (std::isfinite(at) && at > 0) {
          const int step = static_cast<int>(rng.next() % 3) - 1;
          const float cut = step < 0 ? std::nextafter(at, 0.0f) : step > 0 ? std::nextafter(at, 1e30f) : at;
          if (rng.uniform() < 0.5f) r.tmax = cut;
          else r.tmin = cut;
        }
        break;
      }
      case 6:  // far outside, towards the scene
      {
        const Vec3f o = center + 50.0f * size * test::random_direction(rng);
        r = Ray(o, inside_point(1.0f) - o);
        break;
      }
      case 7:  // negative tmin, finite tmax
        r = Ray(inside_point(1.0f), test::random_direction(rng), -size * rng.uniform(), size * rng.uniform());
        break;
      default: {  // grazing a vertex from the triangle's own plane
        const Vec3f o = p0 - (rng.uniform() + 0.1f) * e1;
        r = Ray(o, p0 - o + 1e-6f * size * test::random_direction(rng));
        break;
      }
    }
    if (kind != 5 && kind != 7 && rng.uniform() < 0.3f) r.tmax = size * (0.1f + 2.0f * rng.uniform());
    if (ray_is_valid(r)) rays.push_back(r);
  }
  return rays;
}

struct Comparison {
  size_t rays = 0, mismatches = 0, grazing = 0, hits = 0, exact_ties = 0;
  size_t tested = 0;  // triangles the culled search tested, over all rays
  std::string first;
};

Comparison compare(const TriangleMesh& mesh, const std::vector<Ray>& rays, double graze_tol = 1e-5) {
  const OracleIndex index(mesh);
  Comparison c;
  for (const Ray& r : rays) {
    const OracleHit brute = oracle_closest_hit(mesh, r, graze_tol);
    OracleIndexStats stats;
    const OracleHit culled = oracle_closest_hit(index, mesh, r, graze_tol, &stats);
    c.rays++;
    c.tested += stats.triangles_tested;
    c.grazing += brute.grazing;
    c.hits += brute.valid;
    c.exact_ties += brute.exact_tie;
    const bool same = brute.valid == culled.valid && brute.prim == culled.prim && bits(brute.t) == bits(culled.t) &&
                      brute.grazing == culled.grazing && brute.robust_hit == culled.robust_hit &&
                      brute.exact_tie == culled.exact_tie;
    if (!same && c.mismatches++ < 5)
      c.first += fmt::format(
          "  ray org {:a} {:a} {:a} dir {:a} {:a} {:a} t [{:a}, {:a}]: brute valid {} prim {} t {:.17g} grazing {} "
          "robust {} tie {}; culled valid {} prim {} t {:.17g} grazing {} robust {} tie {}\n",
          r.org.x(), r.org.y(), r.org.z(), r.dir.x(), r.dir.y(), r.dir.z(), r.tmin, r.tmax, brute.valid, brute.prim,
          brute.t, brute.grazing, brute.robust_hit, brute.exact_tie, culled.valid, culled.prim, culled.t,
          culled.grazing, culled.robust_hit, culled.exact_tie);
  }
  return c;
}

void expect_identical(const std::string& what, const TriangleMesh& mesh, const std::vector<Ray>& rays,
                      double graze_tol = 1e-5) {
  const Comparison c = compare(mesh, rays, graze_tol);
  EXPECT_EQ(c.mismatches, 0u) << what << ": " << c.mismatches << " of " << c.rays << " rays differ\n" << c.first;
  // The rays must reach the cases compared: some hits, some grazing, some not.
  EXPECT_GT(c.hits, 0u) << what;
  EXPECT_GT(c.grazing, 0u) << what;
  EXPECT_LT(c.grazing, c.rays) << what;
}

TEST(OracleIndex, SameAnswerAsTheBruteLoopOnProceduralScenes) {
  for (const char* spec : {"soup:n=1500", "needles:n=400", "terrain:n=24", "coplanar:n=800", "sphere", "city:n=3",
                           "tetra:level=3", "grass:n=300", "copies:n=50", "sphereflake:level=1"}) {
    const Scene s = load_scene(spec);
    expect_identical(spec, s.mesh, corner_case_rays(s.mesh, 2500, 17));
  }
}

// The stress scenarios' own rays (axis-parallel, +-0 components, origins on
// faces, scenes translated far from the origin, slivers, tiny and huge
// coordinates) on their own scenes.
TEST(OracleIndex, SameAnswerAsTheBruteLoopOnTheStressScenarios) {
  for (const std::string& name : stress_scenario_names()) {
    const StressScenario sc = make_stress_scenario(name, 0.05, 3);
    // Fewer rays on the large scene (the brute loop is the slow side).
    const size_t want = sc.scene.mesh.num_triangles() > 50000 ? 150 : 800;
    std::vector<Ray> rays;
    for (size_t i = 0; i < sc.rays.size() && rays.size() < want; i += 1 + sc.rays.size() / want) rays.push_back(sc.rays[i]);
    const std::vector<Ray> extra = corner_case_rays(sc.scene.mesh, want / 2, 5);
    rays.insert(rays.end(), extra.begin(), extra.end());
    const auto start = std::chrono::steady_clock::now();
    const Comparison c = compare(sc.scene.mesh, rays);
    std::fprintf(stderr, "%s: %zu triangles, %zu rays, %.1f s\n", name.c_str(), sc.scene.mesh.num_triangles(), c.rays,
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    EXPECT_EQ(c.mismatches, 0u) << name << ": " << c.mismatches << " of " << c.rays << " rays differ\n" << c.first;
  }
}

// Tiny triangles far from the rays' origins: their grazing region is wide
// (the relative edge functions scale with their angular size), and a coarser
// tolerance widens it further.
TEST(OracleIndex, SameAnswerForTinyFarTrianglesAndOtherTolerances) {
  const Scene tiny = make_triangle_soup(2000, 11, 1e-4f);
  std::vector<Ray> rays = corner_case_rays(tiny.mesh, 3000, 23);
  Pcg32 rng(5, 5);
  for (int i = 0; i < 1000; ++i) {
    const Vec3f o = Vec3f(0.5f, 0.5f, 0.5f) + 40.0f * test::random_direction(rng);
    const Vec3f target(rng.uniform(), rng.uniform(), rng.uniform());
    rays.push_back(Ray(o, target - o));
  }
  expect_identical("tiny far triangles", tiny.mesh, rays);
  const Scene terrain = load_scene("terrain:n=20");
  const std::vector<Ray> trays = corner_case_rays(terrain.mesh, 3000, 29);
  expect_identical("terrain, tolerance 1e-3", terrain.mesh, trays, 1e-3);
  expect_identical("terrain, tolerance 1e-8", terrain.mesh, trays, 1e-8);
}

// Degenerate triangles (repeated vertices, collinear vertices) and slivers
// are kept out of the tree and tested on every ray.
TEST(OracleIndex, DegenerateTrianglesAreTestedOnEveryRay) {
  Scene s = make_triangle_soup(600, 19, 0.2f);
  TriangleMesh& m = s.mesh;
  Pcg32 rng(8, 8);
  for (int i = 0; i < 200; ++i) {
    const Vec3f a(rng.uniform(), rng.uniform(), rng.uniform()), b(rng.uniform(), rng.uniform(), rng.uniform());
    const auto base = static_cast<uint32_t>(m.vertices.size());
    m.vertices.push_back(a);
    m.vertices.push_back(b);
    m.vertices.push_back(0.5f * (a + b));                            // collinear
    m.vertices.push_back(a + 1e-6f * (b - a).cross(Vec3f(0, 0, 1)));  // a sliver
    m.triangles.push_back({base, base + 1, base + 2});
    m.triangles.push_back({base, base, base + 1});
    m.triangles.push_back({base, base + 1, base + 3});
  }
  const OracleIndex index(m);
  EXPECT_GE(index.unbounded().size() + index.degenerate().size(), 600u);
  EXPECT_GE(index.degenerate().size(), 200u);  // at least the repeated vertices
  EXPECT_EQ(index.ids().size() + index.unbounded().size() + index.degenerate().size(), m.num_triangles());
  // Exactly collinear: repeated vertices and points on an axis-aligned line.
  EXPECT_TRUE(oracle_triangle_is_exactly_degenerate(Vec3f(1, 2, 3), Vec3f(1, 2, 3), Vec3f(4, 5, 6)));
  EXPECT_TRUE(oracle_triangle_is_exactly_degenerate(Vec3f(0.5f, 1, 3), Vec3f(0.5f, 1, 7), Vec3f(0.5f, 1, -2)));
  EXPECT_TRUE(oracle_triangle_is_exactly_degenerate(Vec3f(1e5f, 1e5f, 1e5f), Vec3f(1e5f + 0.0078125f, 1e5f, 1e5f),
                                                    Vec3f(1e5f + 0.015625f, 1e5f, 1e5f)));
  EXPECT_FALSE(oracle_triangle_is_exactly_degenerate(Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1e-30f, 0)));
  std::vector<Ray> rays = corner_case_rays(m, 4000, 31);
  expect_identical("degenerate triangles", m, rays);
}

// A terrain moved far from the origin: its vertices collapse on the float
// grid (spacing 1/16 at 1e6, twice the cell), so most triangles are exactly
// degenerate.
TEST(OracleIndex, SameAnswerOnACollapsedFarTerrain) {
  Scene s = load_scene("terrain:n=60");
  for (Vec3f& v : s.mesh.vertices) v += Vec3f(1e6f, 1e6f, 1e6f);
  const OracleIndex index(s.mesh);
  EXPECT_GT(index.degenerate().size(), s.mesh.num_triangles() / 3);
  // Few rays: the loop over every triangle decides each degenerate one exactly.
  expect_identical("terrain at 1e6", s.mesh, corner_case_rays(s.mesh, 250, 37));
}

// The point of the index: on a larger scene a call tests a small share of
// the triangles (the rays hit or pass near the terrain from above it). The
// share depends on how much the normals vary within a node: a smooth terrain
// (few noise octaves) needs few, the default rough one more.
double tested_share(const char* spec, double max_share) {
  const Scene s = load_scene(spec);
  const OracleIndex index(s.mesh);
  EXPECT_TRUE(index.unbounded().empty());
  EXPECT_LE(index.memory_bytes(), static_cast<size_t>(kOracleIndexBytesPerTriangle * s.mesh.num_triangles()));
  Pcg32 rng(2, 2);
  size_t tested = 0, rays = 0, mismatches = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3f o(2 * rng.uniform() - 1, 0.5f + rng.uniform(), 2 * rng.uniform() - 1);
    const Vec3f target(2 * rng.uniform() - 1, 0.0f, 2 * rng.uniform() - 1);
    const Ray r(o, target - o);
    OracleIndexStats stats;
    const OracleHit culled = oracle_closest_hit(index, s.mesh, r, 1e-5, &stats);
    const OracleHit brute = oracle_closest_hit(s.mesh, r);
    mismatches += culled.valid != brute.valid || culled.prim != brute.prim || bits(culled.t) != bits(brute.t) ||
                  culled.grazing != brute.grazing || culled.robust_hit != brute.robust_hit;
    tested += stats.triangles_tested;
    rays++;
  }
  EXPECT_EQ(mismatches, 0u) << spec;
  const double share = static_cast<double>(tested) / static_cast<double>(rays * s.mesh.num_triangles());
  EXPECT_LT(share, max_share) << spec << ": tested " << tested / rays << " triangles per ray of " << s.mesh.num_triangles();
  return share;
}

TEST(OracleIndex, TestsFarFewerTrianglesThanTheMeshHolds) {
  tested_share("terrain:n=160,octaves=3", 0.1);  // 51,200 triangles; measured 0.068
  tested_share("terrain:n=160", 0.3);  // measured 0.19
}

}  // namespace
}  // namespace raylab
