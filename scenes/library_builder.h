#pragma once
// Small helpers shared by the procedural library: adding materials, boxes,
// quads and meshes to a scene, and a deterministic random source.
#include <array>
#include <cmath>
#include <cstdint>
#include <random>

#include "scenes/scene.h"

namespace raylab::library {

inline uint32_t add_material(Scene& s, const Vec3f& albedo, const Vec3f& emission = Vec3f::Zero()) {
  s.materials.push_back(Material{albedo, emission});
  return static_cast<uint32_t>(s.materials.size() - 1);
}

inline uint32_t add_vertex(Scene& s, const Vec3f& p) {
  s.mesh.vertices.push_back(p);
  return static_cast<uint32_t>(s.mesh.vertices.size() - 1);
}

inline void add_triangle(Scene& s, uint32_t a, uint32_t b, uint32_t c, uint32_t material) {
  s.mesh.triangles.push_back({a, b, c});
  s.material_ids.push_back(material);
}

// Quad a b c d (counter-clockwise seen from the front) as two triangles.
inline void add_quad(Scene& s, const Vec3f& a, const Vec3f& b, const Vec3f& c, const Vec3f& d, uint32_t material) {
  const uint32_t i = add_vertex(s, a), j = add_vertex(s, b), k = add_vertex(s, c), l = add_vertex(s, d);
  add_triangle(s, i, j, k, material);
  add_triangle(s, i, k, l, material);
}

// Closed axis-aligned box, 8 shared vertices, 12 outward-facing triangles.
inline void add_box(Scene& s, const Vec3f& lo, const Vec3f& hi, uint32_t material) {
  uint32_t v[8];
  for (int i = 0; i < 8; ++i)
    v[i] = add_vertex(s, Vec3f(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z()));
  // Faces as quads of corner indices (bit 0 = x, bit 1 = y, bit 2 = z), outward.
  static constexpr std::array<std::array<int, 4>, 6> faces = {{
      {0, 4, 6, 2},  // -x
      {1, 3, 7, 5},  // +x
      {0, 1, 5, 4},  // -y
      {2, 6, 7, 3},  // +y
      {0, 2, 3, 1},  // -z
      {4, 5, 7, 6},  // +z
  }};
  for (const auto& f : faces) {
    add_triangle(s, v[f[0]], v[f[1]], v[f[2]], material);
    add_triangle(s, v[f[0]], v[f[2]], v[f[3]], material);
  }
}

// Appends a mesh with one material for all its triangles. (Not
// TriangleMesh::append: it reserves the exact size, which makes many small
// appends quadratic.)
inline void add_mesh(Scene& s, const TriangleMesh& m, uint32_t material) {
  const auto base = static_cast<uint32_t>(s.mesh.vertices.size());
  s.mesh.vertices.insert(s.mesh.vertices.end(), m.vertices.begin(), m.vertices.end());
  for (const auto& t : m.triangles) s.mesh.triangles.push_back({base + t[0], base + t[1], base + t[2]});
  s.material_ids.insert(s.material_ids.end(), m.num_triangles(), material);
}

// Horizontal square ground at height y, facing up (+y).
inline void add_ground(Scene& s, const Vec3f& center, float half, uint32_t material) {
  const float y = center.y();
  add_quad(s, Vec3f(center.x() - half, y, center.z() - half), Vec3f(center.x() - half, y, center.z() + half),
           Vec3f(center.x() + half, y, center.z() + half), Vec3f(center.x() + half, y, center.z() - half), material);
}

// Deterministic random numbers for a seed: the engine's output sequence is
// specified by the standard, unlike the standard distributions.
class Random {
 public:
  explicit Random(uint64_t seed) : engine_(seed) {}
  float uniform() { return static_cast<float>(engine_() >> 40) * 0x1p-24f; }  // [0, 1)
  float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }
  int below(int n) { return static_cast<int>(uniform() * static_cast<float>(n)) % n; }
  // Standard normal by Box-Muller.
  float normal() {
    const float u1 = std::max(uniform(), 1e-7f), u2 = uniform();
    return std::sqrt(-2.0f * std::log(u1)) * std::cos(6.2831853f * u2);
  }

 private:
  std::mt19937_64 engine_;
};

// A view from direction `dir` (need not be normalized) at distance `dist`
// from `at`, y up.
inline View look_at(const Vec3f& at, const Vec3f& dir, float dist, float fov_deg = 45.0f, const Vec3f& up = Vec3f::UnitY()) {
  View v;
  v.at = at;
  v.from = at + dist * dir.normalized();
  v.up = up;
  v.fov_deg = fov_deg;
  v.width = 512;
  v.height = 512;
  return v;
}

// The library's last step: the scene with its default camera, under a
// uniform white sky.
inline Scene with_view(Scene s, const View& view) {
  s.view = view;
  s.background = Vec3f::Constant(1.0f);
  return s;
}

}  // namespace raylab::library
