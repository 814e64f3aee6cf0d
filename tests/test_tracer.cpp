// Path tracer: deterministic images whatever the thread count, and a closed
// white-furnace scene that must converge to its analytic radiance.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "accel/registry.h"
#include "scenes/procedural.h"
#include "tracer/camera.h"
#include "tracer/integrator.h"
#include "tracer/lights.h"

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

TEST(PathTracer, CornellBoxHasRedLeftGreenRightAndLitCeilingLight) {
  const Scene s = make_cornell_box();
  auto accel = make_accelerator("bvh");
  accel->build(s.mesh);
  RenderSettings rs;
  rs.width = 64;
  rs.height = 64;
  rs.spp = 16;
  const Image img = render(s, *accel, rs).image;
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
  auto accel = make_accelerator("bvh");
  accel->build(s.mesh);
  RenderSettings rs;
  rs.width = 24;
  rs.height = 24;
  rs.spp = 128;
  rs.max_depth = 1000;
  const Image img = render(s, *accel, rs).image;
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

}  // namespace
}  // namespace raylab
