// Sierpinski tetrahedron: a regular tetrahedron replaced, `level` times, by
// its four half-size corner copies (as in Haines' SPD "tetra"). 4^level
// tetrahedra, 4^(level+1) triangles, all of the same size.
#include <array>

#include "scenes/library.h"
#include "scenes/library_builder.h"

namespace raylab {

namespace {

using namespace library;

void subdivide(Scene& s, const std::array<Vec3f, 4>& t, int level, uint32_t material) {
  if (level == 0) {
    const uint32_t a = add_vertex(s, t[0]), b = add_vertex(s, t[1]), c = add_vertex(s, t[2]), d = add_vertex(s, t[3]);
    // Outward winding: abc faces away from d (down for the root, whose
    // corners a, b, c run clockwise seen from above); halving towards a
    // corner keeps the orientation, so every child winds the same way.
    add_triangle(s, a, b, c, material);
    add_triangle(s, a, d, b, material);
    add_triangle(s, b, d, c, material);
    add_triangle(s, c, d, a, material);
    return;
  }
  for (int corner = 0; corner < 4; ++corner) {
    std::array<Vec3f, 4> child;
    for (int k = 0; k < 4; ++k) child[k] = 0.5f * (t[corner] + t[k]);
    subdivide(s, child, level - 1, material);
  }
}

}  // namespace

SceneGenerator tetra_generator() {
  return {"tetra", "Sierpinski tetrahedron (Haines' SPD 'tetra'): 4^(level+1) equal triangles, edge 2, base on y=0, on a ground plane",
          {{"level", "6", "subdivision depth (0..11)", integer_in(0, 11)},
           {"ground", "1", "add a ground plane (0: the tetrahedron alone, e.g. for scene files)", boolean_flag()}},
          [](const Params& p) {
            const int level = p.integer("level");
            Scene s;
            const uint32_t mat = add_material(s, Vec3f(0.80f, 0.55f, 0.30f));
            // Regular tetrahedron with edge 2, base on y = 0, apex up.
            const float h = 2.0f * std::sqrt(2.0f / 3.0f), r = 2.0f / std::sqrt(3.0f);
            const std::array<Vec3f, 4> t = {Vec3f(r, 0, 0), Vec3f(-0.5f * r, 0, 0.5f * 2.0f),
                                            Vec3f(-0.5f * r, 0, -0.5f * 2.0f), Vec3f(0, h, 0)};
            subdivide(s, t, level, mat);
            if (p.boolean("ground")) add_ground(s, Vec3f(0, 0, 0), 8.0f, add_material(s, Vec3f::Constant(0.5f)));
            return with_view(std::move(s), look_at(Vec3f(0, 0.6f, 0), Vec3f(1.4f, 0.7f, 2.0f), 4.2f, 40.0f));
          }};
}

}  // namespace raylab
