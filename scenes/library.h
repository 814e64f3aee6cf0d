#pragma once
// The procedural scene library: classic and hard scenes for
// acceleration structures, each deterministic for its parameters (and seed),
// sized by parameters, with a default camera and light (emissive triangles
// or a uniform sky), so `raylab render --scene NAME` gives a sensible image.
//
//   sphereflake  recursive spheres (Haines' SPD "balls"), tessellated
//   terrain      fractal height field (fBm value noise)
//   grass        many thin curved blades on a ground patch
//   stadium      a detailed torus knot inside a huge sparse open stadium
//   city         boxes of very different sizes: towers, houses, roof units, cars
//   tetra        Sierpinski tetrahedron
//   box, plane   unit primitives for scene files
//
// `raylab scenes` lists every parameter with its default and meaning.
#include <vector>

#include "scenes/procedural.h"

namespace raylab {

// Appends the library's generators to the list of procedural scenes.
void append_library_generators(std::vector<SceneGenerator>& out);

// The generators, one per file (scenes/library_*.cpp).
SceneGenerator sphereflake_generator();
SceneGenerator terrain_generator();
SceneGenerator grass_generator();
SceneGenerator stadium_generator();
SceneGenerator city_generator();
SceneGenerator tetra_generator();
SceneGenerator box_generator();
SceneGenerator plane_generator();

}  // namespace raylab
