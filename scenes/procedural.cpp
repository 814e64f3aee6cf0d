#include "scenes/procedural.h"
#include "scenes/library.h"

#include <utility>

#include <fmt/format.h>

namespace raylab {

namespace {

// A bare mesh as a procedural scene: one default material, framed by its
// bounds, under a white sky.
Scene finish_scene(std::string name, TriangleMesh mesh, const Aabb& frame) {
  Scene s;
  s.name = std::move(name);
  s.mesh = std::move(mesh);
  s.materials = {Material{}};
  s.material_ids.assign(s.mesh.num_triangles(), 0);
  s.view = frame_bounds(frame);
  s.background = Vec3f::Constant(1.0f);
  return s;
}

}  // namespace

Scene make_triangle_soup(size_t n, uint64_t seed, float size) {
  return finish_scene(fmt::format("soup:n={},seed={}", n, seed), triangle_soup_mesh(n, seed, size),
                      Aabb(Vec3f::Zero(), Vec3f::Ones()));
}

Scene make_triangle_copies(size_t n) {
  TriangleMesh m = triangle_copies_mesh(n);
  const Aabb frame = m.bounds();
  return finish_scene(fmt::format("copies:n={}", n), std::move(m), frame);
}

Scene make_coplanar_scene(size_t n, int grid, int axis, uint64_t seed) {
  TriangleMesh m = coplanar_mesh(n, grid, axis, seed);
  const Aabb frame = m.bounds();
  return finish_scene(fmt::format("coplanar:n={},grid={},axis={},seed={}", n, grid, axis, seed), std::move(m), frame);
}

const std::vector<SceneGenerator>& scene_generators() {
  static const std::vector<SceneGenerator> generators = [] {
  std::vector<SceneGenerator> list = {
      {"cornell", "the Cornell box from the published measurements (32 triangles, area light)", {},
       [](const Params&) { return make_cornell_box(); }},
      {"soup", "random triangles in the unit cube",
       {{"n", "10000", "number of triangles"},
        seed_param(),
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
        seed_param()},
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
         TriangleMesh m = make_uv_sphere(seg, rings);
         const Aabb frame = m.bounds();
         return finish_scene("", std::move(m), frame);
       }},
  };
  append_library_generators(list);  // scenes/library_*.cpp
  return list;
  }();
  return generators;
}

}  // namespace raylab
