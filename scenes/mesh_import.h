#pragma once
// Mesh files through Assimp: OBJ, PLY, STL, OFF, glTF and anything else
// Assimp reads; triangulated, every mesh merged into one TriangleMesh with
// per-triangle materials.
#include <stdexcept>
#include <string>

#include "scenes/scene.h"

namespace raylab {

// Thrown for unreadable, malformed or empty files; the message names the file.
class SceneLoadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Loads a mesh file into a scene with a default camera framing its bounds and
// a uniform sky as default light. The camera comes, by priority, from
//   1. a file NAME.json next to NAME.ext with a view ("from", "at", "up",
//      "fov_deg", "width", "height"), as the SPD scenes in ../shared have;
//   2. the view record of an NFF file (from, at, up, angle, resolution);
//   3. frame_bounds() of the mesh.
// Materials: diffuse colour and emission where the file gives them (OBJ/MTL
// Kd and Ke, glTF baseColorFactor and emissiveFactor, NFF fill colour), a
// default grey otherwise. Every error names the file and what is wrong.
Scene load_mesh_file(const std::string& path);

// The view file next to a mesh (NAME.json for NAME.ext), applied to `view`
// if it exists (a scene file of that name, with "meshes", is not a view file). Throws SceneLoadError naming the view file when it is invalid.
void apply_sibling_view_file(const std::string& mesh_path, View& view);

}  // namespace raylab
