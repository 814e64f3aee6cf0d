#include "base/mesh_shapes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <random>

#include "base/pcg.h"

namespace raylab {

namespace {

// Deterministic uniform float in [0, 1) from a 64-bit engine (the standard
// distributions are not specified bit-for-bit across library versions).
float uniform01(std::mt19937_64& rng) { return static_cast<float>(rng() >> 40) * 0x1p-24f; }

}  // namespace

void append_triangle(TriangleMesh& m, const Vec3f& a, const Vec3f& b, const Vec3f& c) {
  const auto base = static_cast<uint32_t>(m.vertices.size());
  m.vertices.insert(m.vertices.end(), {a, b, c});
  m.triangles.push_back({base, base + 1, base + 2});
}

TriangleMesh triangle_soup_mesh(size_t n, uint64_t seed, float size) {
  TriangleMesh m;
  std::mt19937_64 rng(seed);
  const float extent = size * 2.0f / std::cbrt(static_cast<float>(std::max<size_t>(n, 1)));
  m.vertices.reserve(3 * n);
  m.triangles.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec3f c(uniform01(rng), uniform01(rng), uniform01(rng));
    std::array<Vec3f, 3> p;
    for (Vec3f& q : p) {
      const Vec3f d(uniform01(rng) - 0.5f, uniform01(rng) - 0.5f, uniform01(rng) - 0.5f);
      q = (c + extent * d).cwiseMax(Vec3f::Zero()).cwiseMin(Vec3f::Ones());
    }
    append_triangle(m, p[0], p[1], p[2]);
  }
  return m;
}

TriangleMesh needles_mesh(size_t n, uint64_t seed, float width) {
  TriangleMesh m;
  Pcg32 rng(mix64(seed + 3), 0x511E);
  for (size_t i = 0; i < n; ++i) {
    const int axis = static_cast<int>(i % 3);
    Vec3f a(rng.uniform(), rng.uniform(), rng.uniform()), b(rng.uniform(), rng.uniform(), rng.uniform());
    a[axis] = 0.0f;
    b[axis] = 1.0f;
    Vec3f w = Vec3f::Zero();
    w[(axis + 1) % 3] = width;
    const uint32_t base = static_cast<uint32_t>(m.vertices.size());
    m.vertices.push_back(a);
    m.vertices.push_back(b);
    m.vertices.push_back(a + w);
    m.triangles.push_back({base, base + 1, base + 2});
  }
  return m;
}

TriangleMesh triangle_copies_mesh(size_t n) {
  TriangleMesh m;
  const Vec3f a(0.1f, 0.2f, 0.3f), b(0.9f, 0.35f, 0.5f), c(0.4f, 0.85f, 0.7f);
  for (size_t i = 0; i < n; ++i) append_triangle(m, a, b, c);
  return m;
}

TriangleMesh coplanar_mesh(size_t n, int grid, int axis, uint64_t seed) {
  TriangleMesh m;
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
      m.vertices.push_back(point(static_cast<float>(i) / grid, static_cast<float>(j) / grid));
  auto vid = [grid](int i, int j) { return static_cast<uint32_t>(j * (grid + 1) + i); };
  for (int j = 0; j < grid; ++j)
    for (int i = 0; i < grid; ++i) {
      m.triangles.push_back({vid(i, j), vid(i + 1, j), vid(i + 1, j + 1)});
      m.triangles.push_back({vid(i, j), vid(i + 1, j + 1), vid(i, j + 1)});
    }
  std::mt19937_64 rng(seed);
  const float extent = 2.0f / std::sqrt(static_cast<float>(std::max<size_t>(n, 1)));
  for (size_t t = 0; t < n; ++t) {
    const float cu = uniform01(rng), cv = uniform01(rng);
    std::array<Vec3f, 3> p;
    for (Vec3f& q : p) {
      const float u = std::clamp(cu + extent * (uniform01(rng) - 0.5f), 0.0f, 1.0f);
      const float v = std::clamp(cv + extent * (uniform01(rng) - 0.5f), 0.0f, 1.0f);
      q = point(u, v);
    }
    append_triangle(m, p[0], p[1], p[2]);
  }
  return m;
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

// From the measurements published by the Cornell Program of Computer
// Graphics ("Cornell Box Data"). One change: the light is moved 0.1 mm below
// the ceiling (548.7 instead of 548.8) so the two are not coplanar.
TriangleMesh cornell_box_mesh() {
  using Quad = std::array<std::array<float, 3>, 4>;
  static const Quad quads[] = {
      // Floor, ceiling, back wall.
      {{{552.8f, 0, 0}, {0, 0, 0}, {0, 0, 559.2f}, {549.6f, 0, 559.2f}}},
      {{{556.0f, 548.8f, 0}, {556.0f, 548.8f, 559.2f}, {0, 548.8f, 559.2f}, {0, 548.8f, 0}}},
      {{{549.6f, 0, 559.2f}, {0, 0, 559.2f}, {0, 548.8f, 559.2f}, {556.0f, 548.8f, 559.2f}}},
      // Green wall at x = 0 (camera's right), red wall at x = 552.8 (camera's left).
      {{{0, 0, 559.2f}, {0, 0, 0}, {0, 548.8f, 0}, {0, 548.8f, 559.2f}}},
      {{{552.8f, 0, 0}, {549.6f, 0, 559.2f}, {556.0f, 548.8f, 559.2f}, {556.0f, 548.8f, 0}}},
      // Area light, front face pointing down into the box.
      {{{343.0f, 548.7f, 227.0f}, {343.0f, 548.7f, 332.0f}, {213.0f, 548.7f, 332.0f}, {213.0f, 548.7f, 227.0f}}},
      // Short block.
      {{{130, 165, 65}, {82, 165, 225}, {240, 165, 272}, {290, 165, 114}}},
      {{{290, 0, 114}, {290, 165, 114}, {240, 165, 272}, {240, 0, 272}}},
      {{{130, 0, 65}, {130, 165, 65}, {290, 165, 114}, {290, 0, 114}}},
      {{{82, 0, 225}, {82, 165, 225}, {130, 165, 65}, {130, 0, 65}}},
      {{{240, 0, 272}, {240, 165, 272}, {82, 165, 225}, {82, 0, 225}}},
      // Tall block.
      {{{423, 330, 247}, {265, 330, 296}, {314, 330, 456}, {472, 330, 406}}},
      {{{423, 0, 247}, {423, 330, 247}, {472, 330, 406}, {472, 0, 406}}},
      {{{472, 0, 406}, {472, 330, 406}, {314, 330, 456}, {314, 0, 456}}},
      {{{314, 0, 456}, {314, 330, 456}, {265, 330, 296}, {265, 0, 296}}},
      {{{265, 0, 296}, {265, 330, 296}, {423, 330, 247}, {423, 0, 247}}},
  };
  TriangleMesh m;
  for (const Quad& q : quads) {
    const auto base = static_cast<uint32_t>(m.vertices.size());
    for (const auto& p : q) m.vertices.emplace_back(p[0], p[1], p[2]);
    m.triangles.push_back({base, base + 1, base + 2});
    m.triangles.push_back({base, base + 2, base + 3});
  }
  return m;
}

}  // namespace raylab
