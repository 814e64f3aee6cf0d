#pragma once
// One entry point for --scene: a procedural spec ("cornell", "soup:n=1000"),
// a path to a mesh file, or a path to a JSON scene file (scenes/scene_file.h).
#include <string>

#include "base/spec.h"
#include "scenes/scene.h"

namespace raylab {

// Throws SpecError (unknown scene or parameter) or SceneLoadError (file).
Scene load_scene(const std::string& spec_or_path);

// The procedural scene a spec names ("sphere", "soup:n=1000").
// Throws SpecError for an unknown scene or parameter.
Scene make_procedural_scene(const Spec& spec);

// One line per procedural scene with its parameters, for `raylab scenes`.
std::string describe_scenes();

}  // namespace raylab
