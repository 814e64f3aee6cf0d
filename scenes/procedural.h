#pragma once
// Procedural scenes, created from spec strings such as "soup:n=1000,seed=7".
#include <functional>
#include <string>
#include <vector>

#include "base/mesh_shapes.h"
#include "base/spec.h"
#include "scenes/scene.h"

namespace raylab {

struct SceneGenerator {
  std::string name;
  std::string help;
  std::vector<ParamInfo> params;
  std::function<Scene(const Params&)> make;
};

const std::vector<SceneGenerator>& scene_generators();

// The `seed` parameter every random generator declares.
inline ParamInfo seed_param() { return ParamInfo{"seed", "1", "random seed", integer_in(-kUnbounded, kUnbounded)}; }

// The Cornell box from Cornell's published measurements (millimetres): two
// white blocks, a red wall on the camera's left, a green one on its right,
// and the area light just below the ceiling; with the published camera.
Scene make_cornell_box();

// The meshes of base/mesh_shapes.h as scenes (one default material, a
// camera framing them, a white sky).
Scene make_triangle_soup(size_t n, uint64_t seed, float size = 1.0f);
Scene make_triangle_copies(size_t n);
Scene make_coplanar_scene(size_t n, int grid, int axis, uint64_t seed);
// needles_mesh(n, seed, width) plus a soup of `soup` triangles.
Scene make_needles_scene(size_t n, size_t soup, uint64_t seed, float width);

}  // namespace raylab
