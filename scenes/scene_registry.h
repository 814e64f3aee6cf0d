#pragma once
// One entry point for --scene: a procedural spec ("cornell", "soup:n=1000")
// or a path to a mesh file.
#include <string>

#include "scenes/scene.h"

namespace raylab {

// Throws SpecError (unknown scene or parameter) or SceneLoadError (file).
Scene load_scene(const std::string& spec_or_path);

// One line per procedural scene with its parameters, for `raylab scenes`.
std::string describe_scenes();

}  // namespace raylab
