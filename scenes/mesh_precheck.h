#pragma once
// Cheap checks of a mesh file's own declarations before it reaches the
// importer: a PLY or OFF header states how many vertices and faces follow,
// so a truncated file or an absurd count is detected here with a precise
// message (Assimp would silently load part of it, or fail obscurely).
#include <cstdint>
#include <string>

namespace raylab {

// Throws SceneLoadError when the file cannot hold what its header declares.
// PLY: header counts against the data size (binary) or line count (ASCII).
// OFF: everything (counts, coordinates, face sizes, indices in range).
// STL: binary size = 84 + 50 x count; ASCII ends with 'endsolid'.
// glTF 2.0 (.gltf, .glb): see precheck_gltf. Other formats pass unchecked.
void precheck_mesh_file(const std::string& path);

// glTF 2.0: JSON syntax (with line and column), asset.version 2.x, every
// buffer holds its byteLength, views and accessors lie inside their buffers,
// and every index of a triangle primitive is below its POSITION count
// (Assimp 5.2 silently drops triangles with out-of-range indices).
void precheck_gltf(const std::string& path, uint64_t file_size);

}  // namespace raylab
