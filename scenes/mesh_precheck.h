#pragma once
// Cheap checks of a mesh file's own declarations before it reaches the
// importer: a PLY or OFF header states how many vertices and faces follow,
// so a truncated file or an absurd count is detected here with a precise
// message (Assimp would silently load part of it, or fail obscurely).
#include <string>

namespace raylab {

// Throws SceneLoadError when the file cannot hold what its header declares.
// Formats other than PLY and OFF pass unchecked.
void precheck_mesh_file(const std::string& path);

}  // namespace raylab
