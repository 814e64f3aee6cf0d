// Grass: many thin curved blades on a square patch of ground. Each blade is a
// tapered strip of `segments` quads (the last one a single triangle) that
// leans and curls in a random direction: long thin triangles, densely
// overlapping in projection, a hard case for spatial subdivision.
#include <cmath>

#include "scenes/library.h"
#include "scenes/library_builder.h"

namespace raylab {

using namespace library;

SceneGenerator grass_generator() {
  return {"grass", "thin curved grass blades on a 2x2 patch: n (2 segments - 1) + 2 triangles",
          {{"n", "30000", "number of blades", integer_in(0, 2e7)},
           seed_param(),
           {"segments", "4", "segments per blade (triangles per blade: 2 segments - 1)", integer_in(1, 64)},
           {"height", "0.12", "mean blade height (the patch is 2 wide)", real_in(0, 10, Ends::OpenLow)},
           {"width", "0.006", "blade width at the root", real_in(0, 1, Ends::OpenLow)}},
          [](const Params& p) {
            const int n = p.integer("n"), segments = p.integer("segments");
            const double height = p.real("height"), width = p.real("width");
            if (static_cast<double>(n) * (2 * segments - 1) > 1e8) throw SpecError("grass: more than 1e8 triangles");
            Random rng(static_cast<uint64_t>(p.integer("seed")));
            Scene s;
            const uint32_t greens[3] = {add_material(s, Vec3f(0.20f, 0.42f, 0.10f)), add_material(s, Vec3f(0.32f, 0.50f, 0.12f)),
                                        add_material(s, Vec3f(0.45f, 0.52f, 0.20f))};
            const uint32_t soil = add_material(s, Vec3f(0.30f, 0.22f, 0.14f));
            s.mesh.vertices.reserve(static_cast<size_t>(n) * (2 * segments + 1) + 4);
            s.mesh.triangles.reserve(static_cast<size_t>(n) * (2 * segments - 1) + 2);
            for (int b = 0; b < n; ++b) {
              const Vec3f root(rng.uniform(-1.0f, 1.0f), 0.0f, rng.uniform(-1.0f, 1.0f));
              const float facing = rng.uniform(0.0f, 6.2831853f);
              const float lean_dir = rng.uniform(0.0f, 6.2831853f);
              const float lean = rng.uniform(0.1f, 0.6f);       // horizontal reach at the tip, relative to the height
              const float h = static_cast<float>(height) * rng.uniform(0.6f, 1.4f);
              const float w = static_cast<float>(width) * rng.uniform(0.7f, 1.3f);
              const Vec3f across(std::cos(facing), 0.0f, std::sin(facing));
              const Vec3f reach(std::cos(lean_dir), 0.0f, std::sin(lean_dir));
              const uint32_t material = greens[rng.below(3)];
              const auto base = static_cast<uint32_t>(s.mesh.vertices.size());
              for (int k = 0; k <= segments; ++k) {
                const float t = static_cast<float>(k) / static_cast<float>(segments);
                // Height grows like sin, reach like t^2: the blade curls over.
                const Vec3f spine = root + Vec3f(0.0f, h * std::sin(t * 1.3f) / std::sin(1.3f), 0.0f) + (lean * h * t * t) * reach;
                if (k == segments) {
                  s.mesh.vertices.push_back(spine);  // the tip
                } else {
                  const float half = 0.5f * w * (1.0f - t);
                  s.mesh.vertices.push_back(spine - half * across);
                  s.mesh.vertices.push_back(spine + half * across);
                }
              }
              for (int k = 0; k < segments; ++k) {
                const uint32_t l0 = base + 2 * k, r0 = l0 + 1;
                if (k + 1 == segments) {
                  add_triangle(s, l0, r0, l0 + 2, material);
                } else {
                  add_triangle(s, l0, r0, r0 + 2, material);
                  add_triangle(s, l0, r0 + 2, l0 + 2, material);
                }
              }
            }
            add_ground(s, Vec3f::Zero(), 1.0f, soil);
            return with_view(std::move(s), look_at(Vec3f(0.0f, 0.02f, 0.35f), Vec3f(0.35f, 0.35f, 1.0f), 1.25f, 40.0f));
          }};
}

}  // namespace raylab
