#include "scenes/scene_registry.h"

#include <filesystem>

#include <fmt/format.h>

#include "scenes/mesh_import.h"
#include "scenes/procedural.h"
#include "scenes/scene_file.h"

namespace raylab {

namespace {

bool is_json_path(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".json";
}

}  // namespace

Scene make_procedural_scene(const Spec& spec) {
  for (const auto& g : scene_generators()) {
    if (g.name != spec.name) continue;
    Scene s = g.make(Params(g.name, g.params, spec.params));
    s.name = spec.to_string();
    s.validate();
    return s;
  }
  std::string names;
  for (const auto& g : scene_generators()) names += (names.empty() ? "" : ", ") + g.name;
  throw SpecError(fmt::format("unknown scene '{}' (procedural scenes: {}; or a mesh or scene file path)", spec.name, names));
}

Scene load_scene(const std::string& text) {
  std::error_code ec;
  // symlink_status: a dangling link is still "given as a file" (and fails there).
  if (std::filesystem::exists(std::filesystem::symlink_status(text, ec)))
    return is_json_path(text) ? load_scene_file(text) : load_mesh_file(text);
  const Spec spec = Spec::parse(text);
  for (const auto& g : scene_generators())
    if (g.name == spec.name) return make_procedural_scene(spec);
  if (text.find('/') != std::string::npos || text.find('.') != std::string::npos)
    throw SceneLoadError(fmt::format("{}: no such file", text));
  return make_procedural_scene(spec);  // throws the unknown-scene error
}

std::string describe_scenes() {
  std::string s;
  for (const auto& g : scene_generators()) {
    s += fmt::format("{:<12} {}\n", g.name, g.help);
    for (const auto& p : g.params) s += fmt::format("    {:<18} {}\n", p.name + "=" + p.default_value, p.help);
  }
  s += "Any mesh file Assimp reads (OBJ, PLY, STL, OFF, glTF 2.0, NFF, ...) can be given as a path,\n"
       "and so can a JSON scene file (see README, 'Scene files').\n";
  return s;
}

}  // namespace raylab
