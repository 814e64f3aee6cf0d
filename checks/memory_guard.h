#pragma once
// One memory rule for every command that builds structures (verify, stress,
// render, show, info, bench): the peak of each step (a structure's build, the
// reference, the stored rays and answers) is estimated before the step runs
// (checks/memory_estimate.h) and compared with what the process may still
// allocate (checks/process_memory.h). A step that does not fit is not started:
// the caller skips it or stops with the guard's one-line message, which names
// the estimate, the memory available and what would fit, instead of being
// killed half-way by the kernel's OOM killer (exit 137, nothing written).
//
// RAYLAB_MEMORY_LIMIT (e.g. "2G", "300M", "65536K", bytes without a suffix)
// caps the memory the guard believes is available: what a test uses to force
// the guard on a small scene, and a way to leave room for other jobs.
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "base/triangle_mesh.h"

namespace raylab {

inline constexpr const char* kMemoryLimitVariable = "RAYLAB_MEMORY_LIMIT";

// The share of the available memory a step's estimate may use (bench's
// --memory-headroom): the estimates are measured peaks rounded up, and the
// rest of the machine moves while a long build runs.
inline constexpr double kDefaultMemoryHeadroom = 0.95;

// "2G", "1.5GiB", "300M", "64K", "1000000" -> bytes (binary units); throws
// std::invalid_argument naming the text otherwise.
size_t parse_byte_size(const std::string& text);

// What the process may still allocate, and where that figure comes from.
struct MemoryRoom {
  size_t bytes = 0;
  std::string source;  // "MemAvailable", "cgroup memory.max", "RAYLAB_MEMORY_LIMIT=300M"
};

// available_memory_bytes() (MemAvailable and the cgroup's memory.max),
// capped by RAYLAB_MEMORY_LIMIT when it is set.
MemoryRoom memory_room();

// One step of a run whose peak is estimated before it starts: fixed_bytes +
// bytes_per_unit x units (units: the scene's triangles for a build, rays for
// stored ray sets), so the guard can say how many units would fit.
struct MemoryStep {
  std::string what;  // "kdtree", "the reference embree:robust=1", "the ray sets"
  size_t bytes = 0;  // the estimated peak above what is resident now
  double bytes_per_unit = 0;
  size_t fixed_bytes = 0;
  size_t units = 0;
  std::string unit;  // "triangles", "rays per set"
  // What to do instead, beyond fewer units ("--reference embree:robust=1,compact=1"); may be empty.
  std::string instead;
  // Where bytes_per_unit comes from ("its registry figure", "1.25 x its peak on a piece of this scene").
  std::string basis;
};

// Building and holding one structure (and one ray set's answers from it) on
// `triangles` triangles, from its registry figure.
MemoryStep structure_step(const std::string& accel_spec, size_t triangles, size_t answers_per_set = 0);

// The same on this mesh: from kProbeFromTriangles triangles on, the figure
// is measured on a piece of the mesh (checks/memory_probe.h; once per spec
// and mesh), else the registry's.
MemoryStep structure_step(const std::string& accel_spec, const TriangleMesh& mesh, size_t answers_per_set = 0);

// Rays and the reference's answers kept for the whole run: `sets` sets of up
// to `rays_per_set` rays.
MemoryStep ray_sets_step(size_t rays_per_set, size_t sets);

// A step that did not fit, as an exception: main() prints its message and
// exits 2 (bad input: the run asked for more than the machine has).
class MemoryShortage : public std::runtime_error {
 public:
  MemoryShortage(const std::string& message, size_t estimate, size_t available)
      : std::runtime_error(message), estimate_bytes(estimate), available_bytes(available) {}
  size_t estimate_bytes, available_bytes;
};

class MemoryGuard {
 public:
  explicit MemoryGuard(double headroom = kDefaultMemoryHeadroom) : headroom_(headroom) {}

  // True when the step's estimate is within the headroom share of the room
  // now plus `released` (memory the caller would free first, e.g. a
  // reference it no longer needs). A headroom of 0 lets everything through.
  bool fits(const MemoryStep& step, size_t released = 0);

  // "kdtree needs ~65.3 GiB by its estimate (700 bytes/triangle x 100,026,368
  // triangles), 19.8 GiB available (MemAvailable); would fit: up to 27,000,000
  // triangles" for the last step checked with fits().
  std::string shortage() const;

  // fits() or throw MemoryShortage("not enough memory for " + shortage()).
  void require(const MemoryStep& step, size_t released = 0);

  size_t last_estimate() const { return last_.bytes; }
  size_t last_available() const { return room_.bytes; }
  double headroom() const { return headroom_; }

 private:
  double headroom_;
  MemoryStep last_;
  MemoryRoom room_;
  size_t released_ = 0;
};

// A run's memory, step by step, as the guard will check it: the loaded
// scene, the stored rays and answers, then one step at a time (the
// reference, each structure; each released before the next, as verify does
// and bench and stress do when two do not fit together). The run's peak is
// the process, the scene, the rays and the largest step: what `raylab memory` prints and
// the workflow asks the scheduler for (mem_mb).
// The process itself beside its data: code, libraries, thread stacks.
inline constexpr size_t kProcessBytes = size_t{128} << 20;

struct MemoryPlan {
  size_t process_bytes = kProcessBytes;
  size_t scene_bytes = 0;
  MemoryStep rays;  // bytes 0 for render, show and info
  std::vector<MemoryStep> steps;
  size_t peak_bytes() const;
};

// Bytes per triangle of a scene not loaded (vertex soup: three vertices of
// its own per triangle, the indices and a material id).
inline constexpr size_t kSceneBytesPerTriangle = 3 * 12 + 12 + 4;

// The plan of `command` (verify, stress, bench, render, show, info) over
// `accel_specs`, with `rays_per_set` rays in each of `sets` ray sets. With a
// mesh the structures' figures may come from probes (structure_step); with
// only a triangle count, from the registry.
MemoryPlan plan_memory(const std::string& command, const std::vector<std::string>& accel_specs, size_t triangles,
                       size_t scene_bytes, size_t rays_per_set, size_t sets, const TriangleMesh* mesh = nullptr,
                       const std::string& reference = "");

// The hook of the commands that build one structure at a time (render, show,
// info): throws MemoryShortage when building `accel_spec` on `triangles`
// triangles is estimated not to fit.
void require_structure_fits(const std::string& accel_spec, const TriangleMesh& mesh);

// "100,026,368"
std::string group_digits(size_t n);

// "31.2 GiB", "300.0 MiB"
std::string format_bytes(double bytes);

}  // namespace raylab
