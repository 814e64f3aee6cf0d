// The procedural scene library: every scene is valid, lit, seen by its own
// camera and renders to a non-black image; scenes are deterministic for
// their parameters and seeds, sized exactly by their parameters; closed
// shapes are closed and wound outwards; the hard cases are as hard as they
// claim (sizes spanning orders of magnitude, a dense object in a huge room).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <map>

#include "accel/registry.h"
#include "scenes/procedural.h"
#include "scenes/scene_registry.h"
#include "tests/test_util.h"
#include "tests/tracer_test_util.h"
#include "tracer/camera.h"
#include "tracer/integrator.h"

namespace raylab {
namespace {

Scene make(const std::string& spec) { return load_scene(spec); }

// Small versions of each scene for speed; the defaults are checked by the
// exact-size test and by `raylab render` in the README gallery.
const std::vector<std::string> kLibrary = {
    "cornell",          "soup:n=2000",  "sphere:segments=16,rings=8", "sphereflake:level=2,segments=8",
    "terrain:n=48",     "grass:n=3000", "stadium:along=128,around=12", "city:n=6",
    "tetra:level=3",    "box",          "plane:n=4"};

TEST(SceneLibrary, EverySceneIsValidLitSeenAndRendersToASensibleImage) {
  for (const auto& spec : kLibrary) {
    SCOPED_TRACE(spec);
    const Scene s = make(spec);
    ASSERT_NO_THROW(s.validate());
    EXPECT_GT(s.num_triangles(), 0u);
    EXPECT_EQ(view_problem(s.view), "");
    EXPECT_TRUE(s.has_emitters() || s.background.maxCoeff() > 0.0f) << "no light";
    auto accel = make_accelerator("bvh");
    accel->build(s.mesh);
    EXPECT_GT(test::camera_hit_fraction(s, *accel), 0.15) << "the default camera should look at the scene";
    RenderSettings rs;
    rs.width = rs.height = 24;
    rs.spp = 4;
    const Image img = render(s, *accel, rs).image;
    double sum = 0.0;
    size_t finite = 0;
    for (int y = 0; y < img.height; ++y)
      for (int x = 0; x < img.width; ++x) {
        const Vec3f p = img.pixel(x, y);
        finite += p.allFinite();
        sum += p.sum() / 3.0;
      }
    EXPECT_EQ(finite, static_cast<size_t>(img.width * img.height));
    const double mean = sum / (img.width * img.height);
    EXPECT_GT(mean, 0.02) << "image is black";
    EXPECT_LT(mean, 5.0) << "image is blown out";
  }
}

TEST(SceneLibrary, TriangleCountsFollowTheParameters) {
  auto count = [](const std::string& spec) { return make(spec).num_triangles(); };
  // sphereflake: (9^(L+1) - 1) / 8 spheres of 2 S (S/2 - 1) triangles (+2 for the ground).
  EXPECT_EQ(count("sphereflake:level=0,segments=8,ground=0"), 1u * 2 * 8 * 3);
  EXPECT_EQ(count("sphereflake:level=2,segments=8,ground=0"), 91u * 2 * 8 * 3);
  EXPECT_EQ(count("sphereflake:level=1,segments=16"), 10u * 2 * 16 * 7 + 2);
  EXPECT_EQ(count("sphereflake"), 820u * 2 * 16 * 7 + 2);
  EXPECT_EQ(count("tetra:level=0,ground=0"), 4u);
  EXPECT_EQ(count("tetra:level=5,ground=0"), 4096u);
  EXPECT_EQ(count("tetra"), 16384u + 2);
  EXPECT_EQ(count("terrain:n=10"), 200u);
  EXPECT_EQ(count("terrain"), 2u * 256 * 256);
  EXPECT_EQ(count("grass:n=100,segments=3"), 100u * 5 + 2);
  EXPECT_EQ(count("grass"), 30000u * 7 + 2);
  EXPECT_EQ(count("stadium:along=64,around=8,sectors=10,tiers=3"), 2u * 64 * 8 + 12 + 2 + 12u * 10 * 3);
  EXPECT_EQ(count("plane:n=3"), 18u);
  EXPECT_EQ(count("box"), 12u);
  EXPECT_GT(count("city:n=2"), count("city:n=1"));
  EXPECT_THROW(make("tetra:level=12"), SpecError);
  EXPECT_THROW(make("sphereflake:level=9"), SpecError);
  EXPECT_THROW(make("terrain:roughness=1.5"), SpecError);
  EXPECT_THROW(make("grass:n=-1"), SpecError);
  EXPECT_THROW(make("stadium:ratio=1"), SpecError);
  EXPECT_THROW(make("city:n=0"), SpecError);
}

TEST(SceneLibrary, DeterministicForASeedAndDifferentAcrossSeeds) {
  for (const std::string base : {"terrain:n=32", "grass:n=500", "city:n=3", "soup:n=100"}) {
    SCOPED_TRACE(base);
    const Scene a = make(base + ",seed=3"), b = make(base + ",seed=3"), c = make(base + ",seed=4");
    EXPECT_EQ(a.mesh.vertices, b.mesh.vertices);
    EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
    EXPECT_EQ(a.material_ids, b.material_ids);
    EXPECT_NE(a.mesh.vertices, c.mesh.vertices);
  }
  // Seedless scenes are reproducible too.
  EXPECT_EQ(make("sphereflake:level=1").mesh.vertices, make("sphereflake:level=1").mesh.vertices);
}

// Closed and consistently wound outwards: every directed edge appears once
// and its reverse once, and the signed volume (divergence theorem) is positive.
void expect_closed_outward(const TriangleMesh& m, size_t first, size_t count) {
  std::map<std::pair<Vec3f, Vec3f>, int, bool (*)(const std::pair<Vec3f, Vec3f>&, const std::pair<Vec3f, Vec3f>&)> edges(
      [](const std::pair<Vec3f, Vec3f>& a, const std::pair<Vec3f, Vec3f>& b) {
        const auto key = [](const std::pair<Vec3f, Vec3f>& e) {
          return std::array<float, 6>{e.first.x(), e.first.y(), e.first.z(), e.second.x(), e.second.y(), e.second.z()};
        };
        return key(a) < key(b);
      });
  double volume = 0.0;
  for (size_t t = first; t < first + count; ++t) {
    const Vec3f a = m.vertex(t, 0), b = m.vertex(t, 1), c = m.vertex(t, 2);
    volume += static_cast<double>(a.dot(b.cross(c))) / 6.0;
    ++edges[{a, b}];
    ++edges[{b, c}];
    ++edges[{c, a}];
  }
  size_t unpaired = 0, repeated = 0;
  for (const auto& [e, n] : edges) {
    repeated += n != 1;
    const auto rev = edges.find({e.second, e.first});
    unpaired += rev == edges.end() || rev->second != n;
  }
  EXPECT_EQ(repeated, 0u);
  EXPECT_EQ(unpaired, 0u);
  EXPECT_GT(volume, 0.0);
}

TEST(SceneLibrary, ClosedShapesAreClosedAndWoundOutwards) {
  for (const std::string spec : {"box", "tetra:level=0,ground=0", "tetra:level=3,ground=0", "sphereflake:level=1,segments=8,ground=0",
                                 "sphere:segments=12,rings=6"}) {
    SCOPED_TRACE(spec);
    const Scene s = make(spec);
    expect_closed_outward(s.mesh, 0, s.num_triangles());
  }
  // The stadium's knot tube comes first: closed and outward on its own.
  const Scene st = make("stadium:along=64,around=8,sectors=6,tiers=2");
  SCOPED_TRACE("stadium knot");
  expect_closed_outward(st.mesh, 0, 2 * 64 * 8);
  // The ground-facing surfaces face up.
  const Scene terrain = make("terrain:n=8");
  for (size_t t = 0; t < terrain.num_triangles(); ++t) {
    const Vec3f n = (terrain.mesh.vertex(t, 1) - terrain.mesh.vertex(t, 0)).cross(terrain.mesh.vertex(t, 2) - terrain.mesh.vertex(t, 0));
    EXPECT_GT(n.y(), 0.0f) << t;
  }
}

TEST(SceneLibrary, HardCasesAreAsHardAsTheyClaim) {
  // Stadium: almost every triangle within a unit of the object, in a room ~1000 across.
  const Scene st = make("stadium");
  size_t near_object = 0;
  for (size_t t = 0; t < st.num_triangles(); ++t)
    near_object += (st.mesh.triangle_bounds(t).center() - Vec3f(0, 0.5f, 0)).norm() < 1.0f;
  EXPECT_GT(static_cast<double>(near_object) / st.num_triangles(), 0.9);
  EXPECT_GT(st.bounds().diagonal().maxCoeff(), 900.0f);
  // City: triangle areas span more than four orders of magnitude (cars to towers and the ground).
  // Grass: blades are slivers (long thin triangles).
  auto area_and_aspect = [](const Scene& s, float& min_area, float& max_area, float& max_aspect) {
    min_area = 1e30f, max_area = 0.0f, max_aspect = 0.0f;
    for (size_t t = 0; t < s.num_triangles(); ++t) {
      const Vec3f a = s.mesh.vertex(t, 0), b = s.mesh.vertex(t, 1), c = s.mesh.vertex(t, 2);
      const float area = 0.5f * (b - a).cross(c - a).norm();
      const float longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
      min_area = std::min(min_area, area);
      max_area = std::max(max_area, area);
      if (area > 0) max_aspect = std::max(max_aspect, longest * longest / (2.0f * area));
    }
  };
  float lo, hi, aspect;
  area_and_aspect(make("city"), lo, hi, aspect);
  EXPECT_GT(hi / lo, 1e4f);
  area_and_aspect(make("grass:n=2000"), lo, hi, aspect);
  EXPECT_GT(aspect, 20.0f);
}

TEST(SceneLibrary, ScenesCommandListsEveryGeneratorWithItsParameters) {
  const auto r = test::run_raylab("scenes");
  EXPECT_EQ(r.exit_code, 0);
  for (const auto& g : scene_generators()) {
    EXPECT_THAT(r.output, ::testing::HasSubstr(g.name + " ")) << g.name;
    for (const auto& p : g.params) EXPECT_THAT(r.output, ::testing::HasSubstr(p.name + "=" + p.default_value)) << g.name;
  }
}

}  // namespace
}  // namespace raylab
