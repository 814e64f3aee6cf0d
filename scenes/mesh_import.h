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
// a uniform sky as default light. If a file NAME.json sits next to NAME.ext
// with a view ("from", "at", "up", "fov_deg", "width", "height", as the SPD
// scenes have), that view is used.
Scene load_mesh_file(const std::string& path);

}  // namespace raylab
