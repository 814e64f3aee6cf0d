#pragma once
// Procedural scenes, created from spec strings such as "soup:n=1000,seed=7".
#include <functional>
#include <string>
#include <vector>

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

// The Cornell box from Cornell's published measurements (millimetres): two
// white blocks, a red wall on the camera's left, a green one on its right,
// and the area light just below the ceiling; with the published camera.
Scene make_cornell_box();

// n random triangles in the unit cube, deterministic for a seed.
Scene make_triangle_soup(size_t n, uint64_t seed, float size = 1.0f);

// n identical copies of one (not axis-aligned) triangle, each with its own
// three vertices: the degenerate input for spatial subdivisions.
Scene make_triangle_copies(size_t n);

// Everything in one axis-aligned plane (axis = 0, 1 or 2, at coordinate 0.5):
// a regular grid x grid of quads (two triangles each, shared edges) plus n
// random overlapping triangles, all inside the unit square of the plane.
Scene make_coplanar_scene(size_t n, int grid, int axis, uint64_t seed);

// Closed UV sphere: `segments` around, `rings` from pole to pole; vertices
// are shared (one per pole), so the surface is exactly closed: every edge
// belongs to two triangles with identical endpoint coordinates.
TriangleMesh make_uv_sphere(int segments, int rings, const Vec3f& center = Vec3f::Zero(), float radius = 1.0f);

}  // namespace raylab
