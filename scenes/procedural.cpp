#include "scenes/procedural.h"
#include "scenes/library.h"

#include <cmath>
#include <random>

#include <fmt/format.h>

namespace raylab {

namespace {

// Deterministic uniform float in [0, 1) from a 64-bit engine (the standard
// distributions are not specified bit-for-bit across library versions).
float uniform01(std::mt19937_64& rng) { return static_cast<float>(rng() >> 40) * 0x1p-24f; }

}  // namespace

Scene make_triangle_soup(size_t n, uint64_t seed, float size) {
  Scene s;
  s.name = fmt::format("soup:n={},seed={}", n, seed);
  std::mt19937_64 rng(seed);
  // Triangles whose extent is about `size` times the mean spacing of n
  // points in the unit cube, so density stays comparable across n.
  const float extent = size * 2.0f / std::cbrt(static_cast<float>(std::max<size_t>(n, 1)));
  s.mesh.vertices.reserve(3 * n);
  s.mesh.triangles.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec3f c(uniform01(rng), uniform01(rng), uniform01(rng));
    const auto base = static_cast<uint32_t>(s.mesh.vertices.size());
    for (int k = 0; k < 3; ++k) {
      const Vec3f d(uniform01(rng) - 0.5f, uniform01(rng) - 0.5f, uniform01(rng) - 0.5f);
      Vec3f p = c + extent * d;
      p = p.cwiseMax(Vec3f::Zero()).cwiseMin(Vec3f::Ones());
      s.mesh.vertices.push_back(p);
    }
    s.mesh.triangles.push_back({base, base + 1, base + 2});
  }
  s.materials = {Material{}};
  s.material_ids.assign(n, 0);
  s.view = frame_bounds(Aabb(Vec3f::Zero(), Vec3f::Ones()));
  s.background = Vec3f::Constant(1.0f);
  return s;
}

TriangleMesh make_uv_sphere(int segments, int rings, const Vec3f& center, float radius) {
  segments = std::max(3, segments);
  rings = std::max(2, rings);
  TriangleMesh m;
  m.vertices.push_back(center + Vec3f(0, radius, 0));  // north pole
  for (int r = 1; r < rings; ++r) {
    const double theta = M_PI * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double phi = 2.0 * M_PI * s / segments;
      const Vec3f d(static_cast<float>(std::sin(theta) * std::cos(phi)), static_cast<float>(std::cos(theta)),
                    static_cast<float>(std::sin(theta) * std::sin(phi)));
      m.vertices.push_back(center + radius * d);
    }
  }
  m.vertices.push_back(center - Vec3f(0, radius, 0));  // south pole
  const auto south = static_cast<uint32_t>(m.vertices.size() - 1);
  auto ring_vertex = [&](int r, int s) { return static_cast<uint32_t>(1 + (r - 1) * segments + (s % segments)); };
  // Outward-facing winding (counter-clockwise seen from outside).
  for (int s = 0; s < segments; ++s) m.triangles.push_back({0, ring_vertex(1, s + 1), ring_vertex(1, s)});
  for (int r = 1; r < rings - 1; ++r)
    for (int s = 0; s < segments; ++s) {
      const uint32_t a = ring_vertex(r, s), b = ring_vertex(r, s + 1), c = ring_vertex(r + 1, s), d = ring_vertex(r + 1, s + 1);
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  for (int s = 0; s < segments; ++s) m.triangles.push_back({south, ring_vertex(rings - 1, s), ring_vertex(rings - 1, s + 1)});
  return m;
}

const std::vector<SceneGenerator>& scene_generators() {
  static const std::vector<SceneGenerator> generators = [] {
  std::vector<SceneGenerator> list = {
      {"cornell", "the Cornell box from the published measurements (32 triangles, area light)", {},
       [](const Params&) { return make_cornell_box(); }},
      {"soup", "random triangles in the unit cube",
       {{"n", "10000", "number of triangles"},
        {"seed", "1", "random seed"},
        {"size", "1", "triangle extent relative to the mean spacing"}},
       [](const Params& p) {
         const int n = p.integer("n");
         if (n < 0) throw SpecError("soup: n must be >= 0");
         const double size = p.real("size");
         if (!(size > 0.0)) throw SpecError("soup: size must be > 0");
         Scene s = make_triangle_soup(static_cast<size_t>(n), static_cast<uint64_t>(p.integer("seed")),
                                      static_cast<float>(size));
         return s;
       }},
      {"sphere", "closed tessellated UV sphere of radius 1 at the origin",
       {{"segments", "64", "segments around the axis"}, {"rings", "32", "rings from pole to pole"}},
       [](const Params& p) {
         const int seg = p.integer("segments"), rings = p.integer("rings");
         if (seg < 3 || rings < 2 || static_cast<long>(seg) * rings > 50'000'000L)
           throw SpecError("sphere: need segments >= 3, rings >= 2 and at most 5e7 cells");
         Scene s;
         s.mesh = make_uv_sphere(seg, rings);
         s.materials = {Material{}};
         s.material_ids.assign(s.mesh.num_triangles(), 0);
         s.view = frame_bounds(s.mesh.bounds());
         s.background = Vec3f::Constant(1.0f);
         return s;
       }},
  };
  append_library_generators(list);  // scenes/library_*.cpp
  return list;
  }();
  return generators;
}

}  // namespace raylab
