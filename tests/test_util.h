#pragma once
// Helpers shared by the tests.
#include <cstdlib>
#include <filesystem>
#include <string>

#include "accel/core/ray.h"
#include "accel/core/triangle_mesh.h"
#include "tracer/pcg.h"

namespace raylab::test {

inline std::string shared_dir() { return RAYLAB_SHARED_DIR; }
inline bool have_shared_scenes() { return std::filesystem::exists(shared_dir() + "/scenes/MANIFEST.tsv"); }

// A fresh empty directory under the system temp dir.
inline std::filesystem::path temp_dir(const std::string& name) {
  auto p = std::filesystem::temp_directory_path() / ("raylab_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

struct CommandResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs the raylab binary with arguments (shell syntax) and captures output.
CommandResult run_raylab(const std::string& args);
// The same, with `dir` as the working directory.
CommandResult run_raylab_in(const std::filesystem::path& dir, const std::string& args);

// Random unit vector, uniform on the sphere.
inline Vec3f random_direction(Pcg32& rng) {
  while (true) {
    const Vec3f v(2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1);
    const float n2 = v.squaredNorm();
    if (n2 > 1e-4f && n2 <= 1.0f) return v / std::sqrt(n2);
  }
}

}  // namespace raylab::test
