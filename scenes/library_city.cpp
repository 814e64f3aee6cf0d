// City: boxes of very different sizes. An n x n grid of blocks separated by
// streets; each block is split into lots with buildings whose heights follow
// a heavy-tailed (log-normal) law, taller towards the centre; roof units sit
// on the buildings and small cars in the streets. Box sizes span three to
// four orders of magnitude, and big boxes overlap many small ones in space.
#include <cmath>

#include "scenes/library.h"
#include "scenes/library_builder.h"

namespace raylab {

using namespace library;

SceneGenerator city_generator() {
  return {"city", "n x n blocks of buildings (log-normal heights), roof units and cars: boxes of very different sizes",
          {{"n", "16", "blocks per side", integer_in(1, 1024)},
           seed_param(),
           {"cars", "12", "cars per block", integer_in(0, 1000)},
           {"tall", "1", "height scale of the buildings", real_in(0, 100, Ends::OpenLow)}},
          [](const Params& p) {
            const int n = p.integer("n"), cars = p.integer("cars");
            const double tall = p.real("tall");
            Random rng(static_cast<uint64_t>(p.integer("seed")));
            Scene s;
            const uint32_t asphalt = add_material(s, Vec3f(0.18f, 0.18f, 0.19f));
            const uint32_t pavement = add_material(s, Vec3f(0.50f, 0.50f, 0.48f));
            const uint32_t facades[4] = {add_material(s, Vec3f(0.75f, 0.72f, 0.65f)), add_material(s, Vec3f(0.55f, 0.58f, 0.62f)),
                                         add_material(s, Vec3f(0.70f, 0.55f, 0.45f)), add_material(s, Vec3f(0.40f, 0.42f, 0.48f))};
            const uint32_t roof_unit = add_material(s, Vec3f(0.35f, 0.35f, 0.35f));
            const uint32_t car_paint[4] = {add_material(s, Vec3f(0.70f, 0.10f, 0.08f)), add_material(s, Vec3f(0.10f, 0.20f, 0.60f)),
                                           add_material(s, Vec3f(0.85f, 0.85f, 0.80f)), add_material(s, Vec3f(0.85f, 0.65f, 0.10f))};
            const float block = 1.0f, street = 0.3f, pitch = block + street;
            const float half = 0.5f * pitch * static_cast<float>(n);
            add_ground(s, Vec3f::Zero(), half + street, asphalt);
            for (int bj = 0; bj < n; ++bj)
              for (int bi = 0; bi < n; ++bi) {
                const float x0 = -half + 0.5f * street + pitch * static_cast<float>(bi);
                const float z0 = -half + 0.5f * street + pitch * static_cast<float>(bj);
                add_box(s, Vec3f(x0, 0.0f, z0), Vec3f(x0 + block, 0.02f, z0 + block), pavement);  // the kerb
                // Towers cluster in the middle: the log-normal mean rises towards the centre.
                const float cx = (x0 + 0.5f * block) / (half + 1e-6f), cz = (z0 + 0.5f * block) / (half + 1e-6f);
                const float centrality = std::exp(-2.0f * (cx * cx + cz * cz));
                const int lots = 1 + rng.below(3);
                const float lot = block / static_cast<float>(lots);
                for (int lj = 0; lj < lots; ++lj)
                  for (int li = 0; li < lots; ++li) {
                    const float margin = 0.04f * lot + 0.02f;
                    const float lx0 = x0 + lot * static_cast<float>(li) + margin, lz0 = z0 + lot * static_cast<float>(lj) + margin;
                    const float lx1 = lx0 + lot - 2.0f * margin, lz1 = lz0 + lot - 2.0f * margin;
                    const float h = static_cast<float>(tall) * 0.15f * std::exp(0.9f * rng.normal() + 2.0f * centrality);
                    add_box(s, Vec3f(lx0, 0.02f, lz0), Vec3f(lx1, 0.02f + h, lz1), facades[rng.below(4)]);
                    // Roof units: a few small boxes on top.
                    const int units = rng.below(4);
                    for (int u = 0; u < units; ++u) {
                      const float size = 0.02f + 0.05f * rng.uniform();
                      const float ux = rng.uniform(lx0, std::max(lx0, lx1 - size)), uz = rng.uniform(lz0, std::max(lz0, lz1 - size));
                      add_box(s, Vec3f(ux, 0.02f + h, uz), Vec3f(ux + size, 0.02f + h + 0.6f * size, uz + size), roof_unit);
                    }
                  }
                // Cars along the street on this block's +x side and +z side.
                for (int c = 0; c < cars; ++c) {
                  const bool along_x = rng.uniform() < 0.5f;
                  const float t = rng.uniform(0.0f, block);
                  const float lane = rng.uniform() < 0.5f ? 0.08f : 0.2f;
                  const float len = 0.045f, wid = 0.02f, hgt = 0.015f;
                  const Vec3f lo = along_x ? Vec3f(x0 + t, 0.0f, z0 + block + lane) : Vec3f(x0 + block + lane, 0.0f, z0 + t);
                  const Vec3f ext = along_x ? Vec3f(len, hgt, wid) : Vec3f(wid, hgt, len);
                  add_box(s, lo, lo + ext, car_paint[rng.below(4)]);
                }
              }
            const float span = 2.0f * half;
            return with_view(std::move(s),
                             look_at(Vec3f(0.0f, 0.1f * span, 0.0f), Vec3f(0.8f, 0.62f, 1.0f), 1.05f * span, 45.0f));
          }};
}

}  // namespace raylab
