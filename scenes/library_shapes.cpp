// Unit primitives for scene files: a box and a plane (scale and place them
// with a transform).
#include "scenes/library.h"
#include "scenes/library_builder.h"

namespace raylab {

SceneGenerator box_generator() {
  return {"box", "closed unit cube [-0.5, 0.5]^3 (12 triangles), for scene files", {},
          [](const Params&) {
            Scene s;
            library::add_box(s, Vec3f::Constant(-0.5f), Vec3f::Constant(0.5f), library::add_material(s, Vec3f::Constant(0.7f)));
            const View view = frame_bounds(s.bounds());
            return library::with_view(std::move(s), view);
          }};
}

SceneGenerator plane_generator() {
  return {"plane", "square [-1, 1]^2 in the xz plane facing +y (n x n quads), for scene files",
          {{"n", "1", "quads per side", integer_in(1, 8192)}},
          [](const Params& p) {
            const int n = p.integer("n");
            Scene s;
            const uint32_t mat = library::add_material(s, Vec3f::Constant(0.7f));
            const float step = 2.0f / static_cast<float>(n);
            for (int j = 0; j < n; ++j)
              for (int i = 0; i < n; ++i) {
                const float x = -1.0f + step * static_cast<float>(i), z = -1.0f + step * static_cast<float>(j);
                library::add_quad(s, Vec3f(x, 0, z), Vec3f(x, 0, z + step), Vec3f(x + step, 0, z + step), Vec3f(x + step, 0, z), mat);
              }
            return library::with_view(std::move(s), library::look_at(Vec3f::Zero(), Vec3f(0.3f, 1.0f, 0.8f), 3.5f));
          }};
}

void append_library_generators(std::vector<SceneGenerator>& out) {
  for (auto make : {sphereflake_generator, terrain_generator, grass_generator, stadium_generator, city_generator,
                    tetra_generator, box_generator, plane_generator})
    out.push_back(make());
}

}  // namespace raylab
