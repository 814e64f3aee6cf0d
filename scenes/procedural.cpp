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

Scene make_needles_scene(size_t n, size_t soup, uint64_t seed, float width) {
  TriangleMesh m = needles_mesh(n, seed, width);
  m.append(triangle_soup_mesh(soup, seed, 1.0f));
  return finish_scene(fmt::format("needles:n={},soup={},seed={},width={}", n, soup, seed, width), std::move(m),
                      Aabb(Vec3f::Zero(), Vec3f::Ones()));
}

const std::vector<SceneGenerator>& scene_generators() {
  static const std::vector<SceneGenerator> generators = [] {
  std::vector<SceneGenerator> list = {
      {"cornell", "the Cornell box from the published measurements (32 triangles, area light)", {},
       [](const Params&) { return make_cornell_box(); }},
      {"soup", "random triangles in the unit cube",
       {{"n", "10000", "number of triangles", integer_in(0, kUnbounded)},
        seed_param(),
        {"size", "1", "triangle extent relative to the mean spacing", real_in(0, kUnbounded, Ends::OpenLow)}},
       [](const Params& p) {
         return make_triangle_soup(static_cast<size_t>(p.integer("n")), static_cast<uint64_t>(p.integer("seed")),
                                   static_cast<float>(p.real("size")));
       }},
      {"copies", "n copies of the same triangle (degenerate input for subdivisions)",
       {{"n", "1000", "number of copies", integer_in(0, 5e7)}},
       [](const Params& p) { return make_triangle_copies(static_cast<size_t>(p.integer("n"))); }},
      {"coplanar", "all triangles in one axis-aligned plane: a quad grid plus random overlapping triangles",
       {{"n", "1000", "random triangles", integer_in(0, 5e7)},
        {"grid", "16", "quads per side of the regular grid (0 = none)", integer_in(0, 4096)},
        {"axis", "2", "normal axis of the plane: 0, 1 or 2", integer_of({0, 1, 2})},
        seed_param()},
       [](const Params& p) {
         return make_coplanar_scene(static_cast<size_t>(p.integer("n")), p.integer("grid"), p.integer("axis"),
                                    static_cast<uint64_t>(p.integer("seed")));
       }},
      {"needles", "long thin needles between opposite faces of the unit cube, plus random triangles (stress 'slivers')",
       {{"n", "4000", "needles", integer_in(0, 5e7)},
        {"soup", "2000", "random triangles", integer_in(0, 5e7)},
        seed_param(),
        {"width", "0.0001", "needle width (the cube is 1 wide)", real_in(0, 1, Ends::OpenLow)}},
       [](const Params& p) {
         return make_needles_scene(static_cast<size_t>(p.integer("n")), static_cast<size_t>(p.integer("soup")),
                                   static_cast<uint64_t>(p.integer("seed")), static_cast<float>(p.real("width")));
       }},
      {"sphere", "closed tessellated UV sphere of radius 1 at the origin",
       {{"segments", "64", "segments around the axis", integer_in(3, kUnbounded)},
        {"rings", "32", "rings from pole to pole", integer_in(2, kUnbounded)}},
       [](const Params& p) {
         const int seg = p.integer("segments"), rings = p.integer("rings");
         if (static_cast<long>(seg) * rings > 50'000'000L) throw SpecError("sphere: at most 5e7 cells (segments x rings)");
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
