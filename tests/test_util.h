#pragma once
// Helpers shared by the tests.
#include <cstdlib>
#include <filesystem>
#include <string>

#include "base/ray.h"
#include "base/triangle_mesh.h"
#include "base/pcg.h"

namespace raylab::test {

inline std::string shared_dir() { return RAYLAB_SHARED_DIR; }
// Paths joined by std::filesystem, not by std::string's operator+, whose inlined copies
// GCC 12 flags with false -Warray-bounds / -Wrestrict warnings.
inline bool have_shared_scenes() { return std::filesystem::exists(std::filesystem::path(shared_dir()) / "scenes" / "MANIFEST.tsv"); }

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

// Runs a shell command and captures its standard output (add 2>&1 for stderr).
CommandResult run_shell(const std::string& command);
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

// A ray from outside a closed mesh around `center`, aimed at a point of one
// of `full`'s edges (even i) or at one of its vertices (odd i), coming
// within 60 degrees of the outward radial direction: steeper than any
// face's tilt, so the ray truly crosses the surface there.
inline Ray ray_at_shared_edge(const TriangleMesh& full, const Vec3f& center, size_t i, Pcg32& rng) {
  const size_t tri = rng.next() % full.num_triangles();
  const int corner = static_cast<int>(rng.next() % 3);
  const Vec3f& p = full.vertex(tri, corner);
  const Vec3f& q = full.vertex(tri, (corner + 1) % 3);
  const Vec3f target = (i % 2) ? p : Vec3f(p + rng.uniform() * (q - p));
  const Vec3f radial = (target - center).normalized();
  Vec3f w = random_direction(rng);
  while (w.dot(radial) < 0.5f) w = random_direction(rng);
  const Vec3f org = target + 2.0f * w;
  return Ray(org, (target - org).normalized());
}

}  // namespace raylab::test
