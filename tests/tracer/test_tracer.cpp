// Path tracer: deterministic images whatever the thread count, and a closed
// white-furnace scene that must converge to its analytic radiance.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "accel/registry.h"
#include "scenes/procedural.h"
#include "tracer/camera.h"
#include "tracer/integrator.h"
#include "tracer/lights.h"
#include "tracer/spawn.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

Image render_with_threads(const Scene& s, const std::string& accel_spec, int threads, uint64_t seed) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
  auto accel = make_accelerator(accel_spec);
  accel->build(s.mesh);
  RenderSettings rs;
  rs.width = 48;
  rs.height = 40;
  rs.spp = 6;
  rs.seed = seed;
  return render(s, *accel, rs).image;
}

TEST(PathTracer, SameSeedGivesSameBytesWithOneAndTwoThreads) {
  const Scene s = make_cornell_box();
  const Image a = render_with_threads(s, "bvh", 1, 7);
  const Image b = render_with_threads(s, "bvh", 2, 7);
  EXPECT_EQ(a.rgb, b.rgb);  // bit-identical floats
  EXPECT_EQ(to_srgb8(a), to_srgb8(b));
  const Image c = render_with_threads(s, "bvh", 2, 8);
  EXPECT_NE(a.rgb, c.rgb);  // and the seed matters
  // The accelerator does not change the image either (same hits).
  EXPECT_EQ(a.rgb, render_with_threads(s, "brute", 2, 7).rgb);
}

// The image of a scene rendered with the default BVH.
Image render_square(const Scene& s, int size, int spp, int max_depth = RenderSettings{}.max_depth) {
  auto accel = make_accelerator("bvh");
  accel->build(s.mesh);
  RenderSettings rs;
  rs.width = rs.height = size;
  rs.spp = spp;
  rs.max_depth = max_depth;
  return render(s, *accel, rs).image;
}

TEST(PathTracer, CornellBoxHasRedLeftGreenRightAndLitCeilingLight) {
  const Image img = render_square(make_cornell_box(), 64, 16);
  auto region_mean = [&](int x0, int x1, int y0, int y1) {
    Vec3f sum = Vec3f::Zero();
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) sum += img.pixel(x, y);
    return Vec3f(sum / static_cast<float>((x1 - x0) * (y1 - y0)));
  };
  const Vec3f left = region_mean(2, 8, 20, 40), right = region_mean(56, 62, 20, 40);
  EXPECT_GT(left.x(), 2.0f * left.y()) << "left wall should be red";
  EXPECT_GT(right.y(), 1.5f * right.x()) << "right wall should be green";
  const Vec3f light = img.pixel(32, 9);  // the light spans rows 7.9..10.2 of 64
  EXPECT_GT(light.minCoeff(), 1.0f) << "the light is visible at the top centre";
}

// A closed sphere whose inner surface emits E and reflects with albedo a:
// radiance is E / (1 - a) everywhere (the sum of a geometric series of
// bounces), so every pixel of a camera inside must converge to it.
TEST(PathTracer, WhiteFurnaceConvergesToAnalyticValue) {
  Scene s;
  s.name = "furnace";
  s.mesh = make_uv_sphere(24, 12, Vec3f::Zero(), 2.0f);
  for (auto& t : s.mesh.triangles) std::swap(t[1], t[2]);  // face inwards
  const Vec3f albedo(0.5f, 0.3f, 0.8f);
  const Vec3f emission(0.5f, 0.7f, 0.2f);
  s.materials = {Material{albedo, emission}};
  s.material_ids.assign(s.mesh.num_triangles(), 0);
  s.view.from = Vec3f(0.1f, 0.2f, 0.05f);
  s.view.at = Vec3f(1, 0.3f, 0.4f);
  s.view.fov_deg = 70;
  const Image img = render_square(s, 24, 128, 1000);
  const Vec3f expected = emission.cwiseQuotient(Vec3f::Ones() - albedo);  // (1.0, 1.0, 1.0)
  const Vec3f mean = img.mean();
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], expected[c], 0.02f * expected[c]) << "channel " << c;
}

TEST(Camera, CentreRayLooksAtTarget) {
  View v;
  v.from = Vec3f(1, 2, 3);
  v.at = Vec3f(1, 2, 10);
  v.width = 100;
  v.height = 50;
  const PinholeCamera cam(v);
  const Ray r = cam.generate(50, 25);
  EXPECT_NEAR(r.dir.z(), 1.0f, 1e-6f);
  // Right of the image is -x when looking down +z with +y up (right-handed).
  EXPECT_LT(cam.generate(99, 25).dir.x(), 0.0f);
  EXPECT_GT(cam.generate(50, 0).dir.y(), 0.0f);  // top of the image is up
}

TEST(Lights, SamplingMatchesPowerAndDensity) {
  const Scene s = make_cornell_box();
  const LightSampler lights(s);
  ASSERT_EQ(lights.size(), 2u);
  // The Cornell light is 130 x 105 mm: each of its two triangles has
  // selection 1/2 and area 6825 mm^2, so the area density is 1 / 13650.
  const auto smp = lights.sample(0.3f, 0.5f, 0.5f);
  EXPECT_NEAR(smp.pdf_area, 1.0f / 13650.0f, 1e-9f);
  EXPECT_NEAR(smp.normal.y(), -1.0f, 1e-6f);
  EXPECT_NEAR(smp.point.y(), 548.7f, 1e-3f);
  EXPECT_EQ(lights.pdf_area(0), 0.0f);  // the floor is not a light
}

// The spawn-offset rule (tracer/spawn.h), as pbrt-v4's "reintersect" test:
// random triangles of many sizes far from and near the origin, a ray to a
// random point of each, then rays spawned from the hit into the hemisphere
// of the side it arrived on (and shadow rays to points on that side) must
// never hit the same triangle again.
TEST(SpawnOffset, RaySpawnedFromAHitNeverHitsTheSameTriangleAgain) {
  Pcg32 rng(12345, 7);
  size_t spawned = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const float scale = std::ldexp(1.0f, static_cast<int>(rng.next() % 24) - 12);     // 2^-12 .. 2^11
    const float offset = std::ldexp(1.0f, static_cast<int>(rng.next() % 28) - 10);    // 2^-10 .. 2^17
    const Vec3f center = offset * test::random_direction(rng);
    TriangleMesh mesh;
    for (int c = 0; c < 3; ++c) mesh.vertices.push_back(center + scale * test::random_direction(rng));
    mesh.triangles = {{0, 1, 2}};
    const Vec3f e1 = mesh.vertices[1] - mesh.vertices[0], e2 = mesh.vertices[2] - mesh.vertices[0];
    if (!(e1.cross(e2).norm() > 1e-3f * scale * scale)) continue;  // nearly degenerate: no defined normal
    auto accel = make_accelerator("brute");
    accel->build(mesh);
    Aabb bounds;
    for (const Vec3f& v : mesh.vertices) bounds.extend(v);
    const SpawnOffset spawn(bounds);

    // A ray from a random point at some distance to a random point of the triangle.
    float b1 = rng.uniform(), b2 = rng.uniform();
    if (b1 + b2 > 1.0f) b1 = 1.0f - b1, b2 = 1.0f - b2;
    const Vec3f target = (1.0f - b1 - b2) * mesh.vertices[0] + b1 * mesh.vertices[1] + b2 * mesh.vertices[2];
    const Vec3f from = target + (scale * (1.0f + 10.0f * rng.uniform())) * test::random_direction(rng);
    const Hit hit = accel->intersect1(Ray(from, target - from));
    if (!hit.valid()) continue;  // grazing the edge: nothing to spawn from

    // As the tracer: the hit point from the barycentrics, the geometric normal facing the ray.
    const Vec3f p = (1.0f - hit.u - hit.v) * mesh.vertices[0] + hit.u * mesh.vertices[1] + hit.v * mesh.vertices[2];
    Vec3f n = e1.cross(e2).normalized();
    if (n.dot(target - from) > 0.0f) n = -n;
    const Vec3f origin = spawn.origin(p, n, from);
    for (int k = 0; k < 16; ++k) {
      Vec3f d = test::random_direction(rng);
      if (d.dot(n) < 0.0f) d = -d;
      ASSERT_FALSE(accel->intersect1(Ray(origin, d)).valid())
          << "trial " << trial << " scale " << scale << " offset " << offset << " direction " << k;
      ASSERT_FALSE(accel->occluded1(shadow_ray_to(origin, origin + (scale * 4.0f) * d)))
          << "trial " << trial << " shadow ray " << k;
      ++spawned;
    }
  }
  EXPECT_GT(spawned, 16000u);  // most trials spawn rays
}

}  // namespace
}  // namespace raylab
