#include "scenes/scene_registry.h"

#include <filesystem>

#include <fmt/format.h>

#include "scenes/mesh_import.h"
#include "scenes/procedural.h"

namespace raylab {

Scene load_scene(const std::string& text) {
  std::error_code ec;
  if (std::filesystem::exists(text, ec)) return load_mesh_file(text);
  const Spec spec = Spec::parse(text);
  for (const auto& g : scene_generators()) {
    if (g.name != spec.name) continue;
    Scene s = g.make(Params(g.name, g.params, spec.params));
    s.name = spec.to_string();
    s.validate();
    return s;
  }
  if (text.find('/') != std::string::npos || text.find('.') != std::string::npos)
    throw SceneLoadError(fmt::format("{}: no such file", text));
  std::string names;
  for (const auto& g : scene_generators()) names += (names.empty() ? "" : ", ") + g.name;
  throw SpecError(fmt::format("unknown scene '{}' (procedural scenes: {}; or a mesh file path)", spec.name, names));
}

std::string describe_scenes() {
  std::string s;
  for (const auto& g : scene_generators()) {
    s += fmt::format("{:<10} {}\n", g.name, g.help);
    for (const auto& p : g.params) s += fmt::format("    {}={:<8} {}\n", p.name, p.default_value, p.help);
  }
  s += "Any mesh file Assimp reads (OBJ, PLY, STL, OFF, glTF, ...) can be given as a path.\n";
  return s;
}

}  // namespace raylab
