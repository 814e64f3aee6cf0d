// libFuzzer target: the mesh and scene loading path (prechecks, the Assimp
// import in its child process, the merge into a Scene, JSON scene files).
// The first input byte picks the format (file extension); the rest is the
// file's content. Any exception is an accepted outcome (bad input gives a
// clear error); a crash, a sanitizer report or a hang is a bug.
//
// Scene files that name procedural generators are skipped: a generator with
// huge parameters is slow by design, not a loading bug.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include "scenes/scene_registry.h"

namespace {
const char* const kExtensions[] = {".obj", ".ply", ".stl", ".off", ".gltf", ".glb", ".nff", ".json"};

std::filesystem::path work_dir() {
  static const std::filesystem::path dir = [] {
    auto p = std::filesystem::temp_directory_path() / ("raylab_fuzz_mesh_" + std::to_string(::getpid()));
    std::filesystem::create_directories(p);
    return p;
  }();
  return dir;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1 || size > (1 << 16)) return 0;
  const char* ext = kExtensions[data[0] % (sizeof kExtensions / sizeof kExtensions[0])];
  const std::string content(reinterpret_cast<const char*>(data + 1), size - 1);
  if (std::string(ext) == ".json" && content.find("generator") != std::string::npos) return 0;
  const auto path = work_dir() / (std::string("input") + ext);
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
  }
  try {
    const raylab::Scene s = raylab::load_scene(path.string());
    s.validate();  // whatever loads must be a consistent scene
  } catch (const std::exception&) {
    // A clear error: fine.
  }
  return 0;
}
