#include "scenes/procedural.h"
#include "scenes/library.h"

#include <algorithm>
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

namespace {

Scene finish_scene(Scene s) {
  s.materials = {Material{}};
  s.material_ids.assign(s.mesh.num_triangles(), 0);
  s.view = frame_bounds(s.mesh.bounds());
  s.background = Vec3f::Constant(1.0f);
  return s;
}

}  // namespace

Scene make_triangle_copies(size_t n) {
  Scene s;
  s.name = fmt::format("copies:n={}", n);
  const Vec3f a(0.1f, 0.2f, 0.3f), b(0.9f, 0.35f, 0.5f), c(0.4f, 0.85f, 0.7f);
  for (size_t i = 0; i < n; ++i) {
    const auto base = static_cast<uint32_t>(s.mesh.vertices.size());
    s.mesh.vertices.insert(s.mesh.vertices.end(), {a, b, c});
    s.mesh.triangles.push_back({base, base + 1, base + 2});
  }
  return finish_scene(std::move(s));
}

Scene make_coplanar_scene(size_t n, int grid, int axis, uint64_t seed) {
  Scene s;
  s.name = fmt::format("coplanar:n={},grid={},axis={},seed={}", n, grid, axis, seed);
  // (u, v) in the unit square -> point in the plane coordinate[axis] = 0.5.
  auto point = [axis](float u, float v) {
    Vec3f p;
    p[axis] = 0.5f;
    p[(axis + 1) % 3] = u;
    p[(axis + 2) % 3] = v;
    return p;
  };
  for (int j = 0; grid > 0 && j <= grid; ++j)
    for (int i = 0; i <= grid; ++i)
      s.mesh.vertices.push_back(point(static_cast<float>(i) / grid, static_cast<float>(j) / grid));
  auto vid = [grid](int i, int j) { return static_cast<uint32_t>(j * (grid + 1) + i); };
  for (int j = 0; j < grid; ++j)
    for (int i = 0; i < grid; ++i) {
      s.mesh.triangles.push_back({vid(i, j), vid(i + 1, j), vid(i + 1, j + 1)});
      s.mesh.triangles.push_back({vid(i, j), vid(i + 1, j + 1), vid(i, j + 1)});
    }
  std::mt19937_64 rng(seed);
  const float extent = 2.0f / std::sqrt(static_cast<float>(std::max<size_t>(n, 1)));
  for (size_t t = 0; t < n; ++t) {
    const float cu = uniform01(rng), cv = uniform01(rng);
    const auto base = static_cast<uint32_t>(s.mesh.vertices.size());
    for (int k = 0; k < 3; ++k) {
      const float u = std::clamp(cu + extent * (uniform01(rng) - 0.5f), 0.0f, 1.0f);
      const float v = std::clamp(cv + extent * (uniform01(rng) - 0.5f), 0.0f, 1.0f);
      s.mesh.vertices.push_back(point(u, v));
    }
    s.mesh.triangles.push_back({base, base + 1, base + 2});
  }
  return finish_scene(std::move(s));
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
      {"copies", "n copies of the same triangle (degenerate input for subdivisions)",
       {{"n", "1000", "number of copies"}},
       [](const Params& p) {
         const int n = p.integer("n");
         if (n < 0 || n > 50'000'000) throw SpecError("copies: n must be in 0..5e7");
         return make_triangle_copies(static_cast<size_t>(n));
       }},
      {"coplanar", "all triangles in one axis-aligned plane: a quad grid plus random overlapping triangles",
       {{"n", "1000", "random triangles"},
        {"grid", "16", "quads per side of the regular grid (0 = none)"},
        {"axis", "2", "normal axis of the plane: 0, 1 or 2"},
        {"seed", "1", "random seed"}},
       [](const Params& p) {
         const int n = p.integer("n"), grid = p.integer("grid"), axis = p.integer("axis");
         if (n < 0 || n > 50'000'000) throw SpecError("coplanar: n must be in 0..5e7");
         if (grid < 0 || grid > 4096) throw SpecError("coplanar: grid must be in 0..4096");
         if (axis < 0 || axis > 2) throw SpecError("coplanar: axis must be 0, 1 or 2");
         return make_coplanar_scene(static_cast<size_t>(n), grid, axis, static_cast<uint64_t>(p.integer("seed")));
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
