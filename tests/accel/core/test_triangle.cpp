// Ray-triangle kernels: interior, edge and vertex hits; watertightness of a
// closed sphere's shared edges and vertices.
#include <cmath>
#include <utility>

#include <gtest/gtest.h>

#include "accel/core/intersect_triangle.h"
#include "accel/registry.h"
#include "tests/accel_test_util.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

const Vec3f A(0, 0, 0), B(1, 0, 0), C(0, 1, 0);

bool hit_wt(const Ray& r, float& t, float& u, float& v) {
  return intersect_watertight(WatertightRay(r), A, B, C, r.tmin, r.tmax, t, u, v);
}

TEST(WatertightTriangle, InteriorHitGivesDistanceAndBarycentrics) {
  const Ray r(Vec3f(0.25f, 0.5f, 2.0f), Vec3f(0, 0, -1));
  float t, u, v;
  ASSERT_TRUE(hit_wt(r, t, u, v));
  EXPECT_FLOAT_EQ(t, 2.0f);
  EXPECT_FLOAT_EQ(u, 0.25f);  // weight of B
  EXPECT_FLOAT_EQ(v, 0.5f);   // weight of C
}

TEST(WatertightTriangle, BothSidesAreHit) {
  const Ray r(Vec3f(0.25f, 0.25f, -3.0f), Vec3f(0, 0, 1));
  float t, u, v;
  ASSERT_TRUE(hit_wt(r, t, u, v));
  EXPECT_FLOAT_EQ(t, 3.0f);
}

TEST(WatertightTriangle, EdgesAndVerticesAreHit) {
  float t, u, v;
  for (const Vec3f& p : {Vec3f(0.5f, 0, 0), Vec3f(0, 0.5f, 0), Vec3f(0.5f, 0.5f, 0), A, B, C}) {
    const Ray r(p + Vec3f(0, 0, 1), Vec3f(0, 0, -1));
    EXPECT_TRUE(hit_wt(r, t, u, v)) << "point " << p.transpose();
    EXPECT_FLOAT_EQ(t, 1.0f);
  }
}

TEST(WatertightTriangle, OutsideParallelAndOutOfRangeMiss) {
  float t, u, v;
  EXPECT_FALSE(hit_wt(Ray(Vec3f(0.6f, 0.6f, 1), Vec3f(0, 0, -1)), t, u, v));
  EXPECT_FALSE(hit_wt(Ray(Vec3f(-0.01f, 0.2f, 1), Vec3f(0, 0, -1)), t, u, v));
  EXPECT_FALSE(hit_wt(Ray(Vec3f(0.2f, 0.2f, 1), Vec3f(1, 0, 0)), t, u, v));     // parallel to the plane
  EXPECT_FALSE(hit_wt(Ray(Vec3f(0.2f, 0.2f, 1), Vec3f(0, 0, 1)), t, u, v));     // pointing away
  EXPECT_FALSE(hit_wt(Ray(Vec3f(0.2f, 0.2f, 1), Vec3f(0, 0, -1), 0.0f, 0.5f), t, u, v));  // tmax too short
  EXPECT_FALSE(hit_wt(Ray(Vec3f(0.2f, 0.2f, 1), Vec3f(0, 0, -1), 1.5f), t, u, v));        // tmin too far
}

TEST(WatertightTriangle, DegenerateTriangleIsNeverHit) {
  float t, u, v;
  const WatertightRay w(Ray(Vec3f(0.5f, 0, 1), Vec3f(0, 0, -1)));
  EXPECT_FALSE(intersect_watertight(w, A, B, Vec3f(2, 0, 0), 0, 10, t, u, v));  // collinear
  EXPECT_FALSE(intersect_watertight(w, B, B, B, 0, 10, t, u, v));              // a point
}

// The ray frame of Woop et al.: kz the axis of the largest |d| (ties to the
// lower axis), kx and ky the next ones cyclically, swapped when d[kz] < 0.
// The constructor picks it from packed tables; every sign and tie pattern of
// three components is checked against that definition, with the shear.
TEST(WatertightTriangle, RayFrameIsTheDominantAxisWithWindingKept) {
  const float mags[] = {0.0f, 0.5f, 1.0f, 2.0f};
  int checked = 0;
  for (float mx : mags)
    for (float my : mags)
      for (float mz : mags)
        for (int signs = 0; signs < 8; ++signs) {
          const Vec3f d((signs & 1) ? -mx : mx, (signs & 2) ? -my : my, (signs & 4) ? -mz : mz);
          if (mx == 0.0f && my == 0.0f && mz == 0.0f) continue;
          const WatertightRay w(Ray(Vec3f(1, 2, 3), d));
          int kz = 0;
          if (std::fabs(d[1]) > std::fabs(d[kz])) kz = 1;
          if (std::fabs(d[2]) > std::fabs(d[kz])) kz = 2;
          int kx = (kz + 1) % 3, ky = (kz + 2) % 3;
          if (d[kz] < 0.0f) std::swap(kx, ky);
          ASSERT_EQ(w.kz, kz) << d.transpose();
          ASSERT_EQ(w.kx, kx) << d.transpose();
          ASSERT_EQ(w.ky, ky) << d.transpose();
          ASSERT_EQ(w.sz, 1.0f / d[kz]);
          ASSERT_EQ(w.sx, d[kx] * (1.0f / d[kz]));
          ASSERT_EQ(w.sy, d[ky] * (1.0f / d[kz]));
          ++checked;
        }
  EXPECT_EQ(checked, 63 * 8);  // 4^3 - 1 non-zero magnitude triples, 8 sign patterns each (some are -0)
}

TEST(MollerTrumbore, AgreesWithWatertightInTheInterior) {
  Pcg32 rng(7, 1);
  for (int i = 0; i < 1000; ++i) {
    const Vec3f target(0.05f + 0.4f * rng.uniform(), 0.05f + 0.4f * rng.uniform(), 0);
    const Vec3f org = target + Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, 1.0f + rng.uniform());
    const Ray r(org, (target - org).normalized());
    float t1, u1, v1, t2, u2, v2;
    ASSERT_TRUE(hit_wt(r, t1, u1, v1));
    ASSERT_TRUE(intersect_moller_trumbore(r, A, B, C, r.tmin, r.tmax, t2, u2, v2));
    EXPECT_NEAR(t1, t2, 1e-5f * t1);
    EXPECT_NEAR(u1, u2, 1e-5f);
    EXPECT_NEAR(v1, v2, 1e-5f);
  }
}

TEST(Watertightness, ClosedSphereHasNoLeaksWithWatertightTest) {
  for (const char* spec : {"brute", "bvh"}) {
    EXPECT_EQ(test::closed_sphere_leaks(spec, Vec3f(0.3f, -0.2f, 0.1f), 10000), 0u) << spec;
    // Far from the origin the float spacing is 1/128 of the sphere's radius.
    EXPECT_EQ(test::closed_sphere_leaks(spec, Vec3f(1e5f, -2e4f, 3e4f), 10000), 0u) << spec << " far";
  }
}

TEST(Watertightness, LeakCounterFindsAHole) {
  // The counter is able to fail: one missing triangle lets rays through.
  EXPECT_GT(test::closed_sphere_leaks("bvh", Vec3f::Zero(), 10000, 700), 0u);
}

}  // namespace
}  // namespace raylab
