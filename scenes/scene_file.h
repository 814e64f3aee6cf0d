#pragma once
// Scene files: a small JSON format that places meshes (files or procedural
// generators) with transforms and materials, and sets the camera.
//
//   {
//     "camera": {                      optional; omitted: frame the whole scene
//       "from": [x, y, z],             eye point (required)
//       "at": [x, y, z],               look-at point (required)
//       "up": [x, y, z],               default [0, 1, 0]
//       "fov_deg": 45,                 vertical field of view in degrees, default 45
//       "width": 512, "height": 512    image size in pixels, default 512 x 512
//     },
//     "background": 1.0,               radiance of rays leaving the scene: a number or
//                                      [r, g, b]; default 0 if any material emits, else 1
//                                      (a uniform white sky as the light)
//     "materials": {                   optional named materials
//       "white": {"diffuse": [0.73, 0.71, 0.68]},
//       "lamp":  {"diffuse": 0.5, "emission": [17, 12, 4]}
//     },
//     "meshes": [                      required, at least one
//       {"generator": "cornell"},
//       {"generator": "sphereflake", "params": {"level": 2},
//        "material": "white",
//        "transform": {"scale": 80, "rotate": {"axis": [0, 1, 0], "degrees": 30},
//                      "translate": [180, 80, 170]}},
//       {"file": "models/thing.obj", "material": {"diffuse": [0.2, 0.3, 0.8]},
//        "transform": {"scale": [1, 2, 1], "rotate": [0, 90, 0]}}
//     ]
//   }
//
// Meshes: "file" is a mesh file path relative to the scene file's folder (any
// format load_mesh_file reads; scene files do not nest); "generator" is a
// procedural scene spec ("sphere" or "sphere:segments=32"), with optional
// "params" (an object of numbers, strings or booleans) added to the spec.
// Only the geometry and materials of a mesh are used: its own camera and
// background are not.
//
// Materials: "diffuse" (Lambertian albedo, a number or [r, g, b], each in
// [0, 1)), "emission" (emitted radiance, a number or [r, g, b], >= 0), both
// optional (default diffuse 0.7 grey, no emission). A mesh's "material"
// (a name from "materials" or an inline material object) replaces every
// material of that mesh; without it the mesh keeps the materials of its file
// or generator.
//
// Transforms: p' = translate + R * (scale * p), i.e. scale first, then
// rotate, then translate. "scale" is a number (uniform) or [sx, sy, sz]
// (non-zero; a mirroring scale also reverses the triangles' winding so front
// faces stay front faces). "rotate" is either {"axis": [x, y, z], "degrees": a}
// (right-handed rotation by a degrees about the axis) or [rx, ry, rz]: Euler
// angles in degrees about the fixed x, then y, then z axis (R = Rz Ry Rx).
//
// Every object may also hold a "comment" string, which is ignored. Any other
// key, a wrong type or a value out of range is an error naming the file and
// the JSON pointer of the value, e.g.
//   scene.json: /meshes/1/transform/scale: expected a number or an array of 3 numbers
#include <string>

#include "scenes/scene.h"

namespace raylab {

// Throws SceneLoadError (the message starts with the file name).
Scene load_scene_file(const std::string& path);

}  // namespace raylab
