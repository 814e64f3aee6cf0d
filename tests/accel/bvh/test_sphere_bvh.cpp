// The sphere hierarchy (bvh:bound=sphere): Ritter spheres hold their points,
// the ray-sphere test is conservative, and the hierarchy agrees with brute
// force and reports how much looser its spheres are than the boxes.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "accel/bvh/sphere_bounds.h"
#include "accel/bvh/traverse_sphere_bvh.h"
#include "accel/registry.h"
#include "base/pcg.h"
#include "scenes/procedural.h"
#include "tests/accel_test_util.h"
#include "tests/brute_agreement.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

TEST(SphereBounds, RitterSphereHoldsEveryPoint) {
  Pcg32 rng(3, 3);
  for (int set = 0; set < 50; ++set) {
    std::vector<Vec3f> pts(1 + rng.next() % 40);
    const float scale = std::ldexp(1.0f, static_cast<int>(rng.next() % 40) - 20);
    for (auto& p : pts) p = scale * Vec3f(rng.uniform(), rng.uniform(), rng.uniform()) + Vec3f(1e3f * scale, 0, 0);
    const Sphere s = ritter_sphere(pts);
    for (const auto& p : pts) EXPECT_LE((p.cast<double>() - s.center.cast<double>()).norm(), s.radius);
  }
  EXPECT_LT(ritter_sphere({}).radius, 0.0f);
}

// A ray through a point inside the sphere (or on it) is never rejected,
// whatever the direction's length: it is scaled by 2^k for k in [-120, 100]
// (|dir|^2 then under- or overflows float), the point still at t = 2^-k.
TEST(SphereBounds, RaySphereTestIsConservative) {
  Pcg32 rng(5, 5);
  for (int i = 0; i < 20000; ++i) {
    const float scale = std::ldexp(1.0f, static_cast<int>(rng.next() % 20) - 10);
    SphereNode s{{scale * rng.uniform(), scale * rng.uniform(), 100.0f * scale}, scale * (0.01f + rng.uniform()), 0, 0};
    const Vec3f c(s.c[0], s.c[1], s.c[2]);
    const Vec3f p = c + s.r * test::random_direction(rng) * (i % 2 ? 1.0f : rng.uniform());
    const Vec3f o = p + scale * 50.0f * test::random_direction(rng);
    const int k = i % 4 == 0 ? static_cast<int>(rng.next() % 221) - 120 : 0;  // |dir| < 2^17 before scaling
    const float t_point = std::ldexp(1.0f, -k);
    const Ray ray(o, (p - o) * std::ldexp(1.0f, k), 0.0f, t_point);
    ASSERT_TRUE(ray_is_valid(ray)) << i << " k " << k;
    float t_enter;
    ASSERT_TRUE(ray_sphere_test(SphereRay(ray), s, 0.0f, t_point, t_enter)) << i << " k " << k;
    EXPECT_LE(t_enter, t_point) << i << " k " << k;
  }
}

TEST(SphereBvh, AgreesWithBruteForceAndReportsLooseness) {
  const TriangleMesh mesh = make_triangle_soup(1000, 8).mesh;
  const auto rays = test::rays_at_triangles(mesh, 1500, 6);
  const auto secondary = test::secondary_rays(mesh, rays, 2);
  for (const char* spec : {"bvh:bound=sphere", "bvh:bound=sphere,tri=mt,leaf=1"}) {
    auto a = make_accelerator(spec);
    const BuildStats s = a->build(mesh);
    // Spheres are looser than the boxes of the same nodes.
    EXPECT_GT(s.extra.at("sphere_area_ratio"), 1.0);
    EXPECT_GT(s.extra.at("sphere_volume_ratio"), 1.0);
    if (std::string(spec).find("mt") != std::string::npos) continue;  // MT distances differ from brute's watertight ones
    std::string first;
    EXPECT_EQ(test::count_brute_mismatches(*a, mesh, rays, &first), 0u) << spec << ": " << first;
    EXPECT_EQ(test::count_brute_mismatches(*a, mesh, secondary, &first), 0u) << spec << ": " << first;
  }
  EXPECT_THROW(make_accelerator("bvh:bound=sphere,layout=bvh8"), SpecError);
  EXPECT_THROW(make_accelerator("bvh:bound=cone"), SpecError);
}

}  // namespace
}  // namespace raylab
