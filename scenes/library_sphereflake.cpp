// Sphereflake: Haines' recursive "balls" model (Standard Procedural Databases,
// 1987), tessellated. A sphere of radius r carries nine spheres of radius r/3
// touching it: six around its "equator" and three above it, all in the frame
// of the direction the sphere grew from, and recursively so. The total radius
// stays below 2 (1 + 2 x (1/3 + 1/9 + ...)).
#include <cmath>

#include <fmt/format.h>

#include "scenes/library.h"
#include "scenes/library_builder.h"

namespace raylab {

namespace {

using namespace library;

struct Flake {
  int levels;
  int segments;
  std::vector<uint32_t> level_material;
  Scene& scene;

  void grow(const Vec3f& center, float radius, const Vec3f& axis, int level) {
    add_mesh(scene, make_uv_sphere(segments, std::max(2, segments / 2), center, radius), level_material[level]);
    if (level == levels) return;
    // An orthonormal frame (u, w) around the growth axis.
    const Vec3f helper = std::abs(axis.x()) < 0.9f ? Vec3f::UnitX() : Vec3f::UnitY();
    const Vec3f u = axis.cross(helper).normalized();
    const Vec3f w = axis.cross(u);
    const float child = radius / 3.0f;
    auto place = [&](float azimuth_deg, float elevation_deg) {
      const float a = azimuth_deg * static_cast<float>(M_PI) / 180.0f, e = elevation_deg * static_cast<float>(M_PI) / 180.0f;
      const Vec3f d = (std::cos(e) * (std::cos(a) * u + std::sin(a) * w) + std::sin(e) * axis).normalized();
      grow(center + (radius + child) * d, child, d, level + 1);
    };
    for (int k = 0; k < 6; ++k) place(60.0f * k, 0.0f);
    for (int k = 0; k < 3; ++k) place(30.0f + 120.0f * k, 60.0f);
  }
};

}  // namespace

SceneGenerator sphereflake_generator() {
  return {"sphereflake",
          "recursive spheres (Haines' SPD 'balls'): 9 children of 1/3 the radius per sphere, on a ground plane; root radius 1 at the origin",
          {{"level", "3", "recursion depth (spheres: 1 + 9 + ... + 9^level)", integer_in(0, 7)},
           {"segments", "16", "sphere tessellation: segments around, segments/2 rings", integer_in(4, 1024)},
           {"ground", "1", "add a ground plane (0: the flake alone, e.g. for scene files)", boolean_flag()}},
          [](const Params& p) {
            const int level = p.integer("level"), segments = p.integer("segments");
            const double spheres = (std::pow(9.0, level + 1) - 1.0) / 8.0;
            const double per_sphere = 2.0 * segments * (std::max(2, segments / 2) - 1);
            if (spheres * per_sphere > 1e8) throw SpecError("sphereflake: more than 1e8 triangles; lower level or segments");
            Scene s;
            const std::vector<Vec3f> palette = {Vec3f(0.80f, 0.78f, 0.74f), Vec3f(0.75f, 0.45f, 0.30f),
                                                Vec3f(0.35f, 0.55f, 0.75f), Vec3f(0.55f, 0.70f, 0.40f),
                                                Vec3f(0.80f, 0.70f, 0.35f)};
            std::vector<uint32_t> mats;
            for (int l = 0; l <= level; ++l) mats.push_back(add_material(s, palette[static_cast<size_t>(l) % palette.size()]));
            Flake flake{level, segments, mats, s};
            flake.grow(Vec3f::Zero(), 1.0f, Vec3f::UnitY(), 0);
            const Aabb b = s.bounds();
            if (p.boolean("ground"))
              add_ground(s, Vec3f(0, b.lo.y(), 0), 4.0f * std::max(b.diagonal().x(), b.diagonal().z()), add_material(s, Vec3f::Constant(0.5f)));
            return with_view(std::move(s), look_at(Vec3f(0, 0.1f, 0), Vec3f(1.0f, 0.8f, 1.6f), 6.4f, 40.0f));
          }};
}

}  // namespace raylab
