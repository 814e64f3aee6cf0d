// Fractal terrain: a regular grid height field whose heights are fractional
// Brownian motion (a sum of octaves of value noise, each octave twice the
// frequency and `roughness` times the amplitude of the previous; Musgrave's
// fBm in Ebert et al., "Texturing and Modeling", 1994). Valleys below the
// water line are flat lakes, so the scene mixes flat and rough regions.
#include <cmath>
#include <cstdint>

#include "scenes/library.h"
#include "scenes/library_builder.h"

namespace raylab {

namespace {

using namespace library;

// Lattice value in [-1, 1] from a hash of (seed, octave, x, z) (splitmix64 finaliser).
float lattice(uint64_t seed, int octave, int64_t x, int64_t z) {
  uint64_t h = seed * 0x9E3779B97F4A7C15ull ^ (static_cast<uint64_t>(octave) << 56) ^
               (static_cast<uint64_t>(x) * 0xBF58476D1CE4E5B9ull) ^ (static_cast<uint64_t>(z) * 0x94D049BB133111EBull);
  h ^= h >> 30;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 27;
  h *= 0x94D049BB133111EBull;
  h ^= h >> 31;
  return static_cast<float>(h >> 40) * 0x1p-23f - 1.0f;
}

// Smoothly interpolated value noise (quintic fade, Perlin 2002).
float value_noise(uint64_t seed, int octave, float x, float z) {
  const float fx = std::floor(x), fz = std::floor(z);
  const auto ix = static_cast<int64_t>(fx), iz = static_cast<int64_t>(fz);
  auto fade = [](float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); };
  const float tx = fade(x - fx), tz = fade(z - fz);
  const float a = lattice(seed, octave, ix, iz), b = lattice(seed, octave, ix + 1, iz);
  const float c = lattice(seed, octave, ix, iz + 1), d = lattice(seed, octave, ix + 1, iz + 1);
  return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * tz;
}

}  // namespace

SceneGenerator terrain_generator() {
  return {"terrain", "fractal height field (fBm value noise) on [-1,1]^2 with lakes: 2 n^2 triangles",
          {{"n", "256", "grid cells per side", integer_in(1, 8192)},
           seed_param(),
           {"octaves", "8", "noise octaves (detail levels)", integer_in(1, 24)},
           {"roughness", "0.5", "amplitude ratio between octaves (0..1): higher is rougher", real_in(0, 1, Ends::Open)},
           {"height", "0.35", "height of the relief relative to the width 2", real_in(0, 100)}},
          [](const Params& p) {
            const int n = p.integer("n"), octaves = p.integer("octaves");
            const double roughness = p.real("roughness"), height = p.real("height");
            const auto seed = static_cast<uint64_t>(p.integer("seed"));
            Scene s;
            const uint32_t water = add_material(s, Vec3f(0.10f, 0.22f, 0.35f));
            const uint32_t grass = add_material(s, Vec3f(0.30f, 0.45f, 0.18f));
            const uint32_t rock = add_material(s, Vec3f(0.45f, 0.38f, 0.30f));
            const uint32_t snow = add_material(s, Vec3f(0.90f, 0.90f, 0.92f));
            // Heights: fBm normalised to about [-1, 1], scaled; lakes at the water line.
            const float water_line = -0.15f * static_cast<float>(height);
            const int side = n + 1;
            s.mesh.vertices.reserve(static_cast<size_t>(side) * side);
            float norm = 0.0f;
            for (int o = 0; o < octaves; ++o) norm += static_cast<float>(std::pow(roughness, o));
            for (int j = 0; j < side; ++j)
              for (int i = 0; i < side; ++i) {
                const float x = -1.0f + 2.0f * static_cast<float>(i) / static_cast<float>(n);
                const float z = -1.0f + 2.0f * static_cast<float>(j) / static_cast<float>(n);
                float h = 0.0f, amplitude = 1.0f, frequency = 2.0f;
                for (int o = 0; o < octaves; ++o) {
                  h += amplitude * value_noise(seed, o, frequency * x, frequency * z);
                  amplitude *= static_cast<float>(roughness);
                  frequency *= 2.0f;
                }
                const float y = std::max(water_line, static_cast<float>(height) * h / norm * 1.6f);
                s.mesh.vertices.emplace_back(x, y, z);
              }
            s.mesh.triangles.reserve(2 * static_cast<size_t>(n) * n);
            s.material_ids.reserve(2 * static_cast<size_t>(n) * n);
            const float top = static_cast<float>(height);
            auto material_of = [&](const Vec3f& a, const Vec3f& b, const Vec3f& c) {
              const float y = (a.y() + b.y() + c.y()) / 3.0f;
              if (a.y() <= water_line && b.y() <= water_line && c.y() <= water_line) return water;
              const Vec3f normal = (b - a).cross(c - a).normalized();
              if (y > 0.45f * top) return snow;
              return std::abs(normal.y()) < 0.8f || y > 0.25f * top ? rock : grass;
            };
            for (int j = 0; j < n; ++j)
              for (int i = 0; i < n; ++i) {
                const auto v00 = static_cast<uint32_t>(j * side + i), v10 = v00 + 1;
                const auto v01 = v00 + static_cast<uint32_t>(side), v11 = v01 + 1;
                // Front faces up (+y): counter-clockwise seen from above.
                for (const auto& t : {std::array<uint32_t, 3>{v00, v01, v11}, std::array<uint32_t, 3>{v00, v11, v10}}) {
                  s.mesh.triangles.push_back(t);
                  s.material_ids.push_back(material_of(s.mesh.vertices[t[0]], s.mesh.vertices[t[1]], s.mesh.vertices[t[2]]));
                }
              }
            return with_view(std::move(s), look_at(Vec3f(0, 0, 0.1f), Vec3f(0.9f, 0.75f, 1.5f), 2.9f, 45.0f));
          }};
}

}  // namespace raylab
