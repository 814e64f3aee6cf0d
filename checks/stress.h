#pragma once
// `raylab stress`: named scenarios (a procedural scene plus a ray set chosen
// to break something: precision far from the origin, zero-thickness bounds,
// degenerate triangles, shared edges and vertices, ray corner cases) run
// against every accelerator with Embree (robust mode) as the reference. Every
// disagreement is arbitrated by the oracle (checks/oracle.h, exact arithmetic
// at edges and vertices); `raylab_wrong` and `embree_wrong` are counted
// separately. The watertight scenarios also count leaks: rays that exactly
// cross a closed surface but miss it (or reach its far side), and rays from
// strictly inside that escape.
#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "base/ray.h"
#include "checks/memory_guard.h"
#include "checks/structure_skip.h"
#include "scenes/scene.h"

namespace raylab {

// Per ray of a watertight scenario: what a leak is for it.
enum class LeakKind : uint8_t {
  None = 0,
  Outside = 1,  // aimed at a shared edge or vertex from outside: a leak if it exactly crosses yet misses
  Inside = 2,   // from strictly inside a closed mesh: a leak if it escapes
};

struct StressScenario {
  std::string name;
  std::string description;
  Scene scene;
  std::vector<Ray> rays;
  std::vector<LeakKind> leak_kind;        // empty, or one per ray (watertight scenarios)
  std::vector<uint8_t> must_not_hit;      // empty, or one flag per triangle (degenerate triangles)
  bool watertight() const { return !leak_kind.empty(); }
};

// Every scenario name, in run order.
const std::vector<std::string>& stress_scenario_names();

// One-line description per scenario, for --help and the README.
std::string describe_stress_scenarios();

// Expands a comma list of names or prefixes ("watertight" selects every
// watertight_* scenario, "all" everything); throws SpecError for unknown names.
std::vector<std::string> expand_stress_scenarios(const std::string& list);

// Builds one scenario; `rays` scales the ray count (the default sizes are
// chosen so that `raylab stress` runs every scenario for every accelerator
// in a few minutes on 2 cores). `scene_spec` (any scene load_scene takes)
// replaces the Cornell box of the scenarios built on it (rays, far_*, tiny,
// huge: stress_scenario_takes_scene); the others throw SpecError with it.
StressScenario make_stress_scenario(const std::string& name, double ray_scale = 1.0, uint64_t seed = 1,
                                    const std::string& scene_spec = "");
bool stress_scenario_takes_scene(const std::string& name);

// Closed meshes with shared vertices, for the watertight scenarios.
TriangleMesh make_closed_box(int n, const Vec3f& center, float half);
TriangleMesh make_torus(int segments, int rings, const Vec3f& center, float major, float minor);

struct StressRecord {
  std::string scenario, accel, status, error;
  size_t triangles = 0;
  size_t rays = 0;          // rays traced by this accelerator (fewer than the scenario's when slow)
  bool subsampled = false;  // too slow for the time budget: a strided subset of the rays was traced
  double build_ms = 0.0;
  size_t bytes = 0;
  // The reference here is robust Embree (StressOptions::reference), not
  // bench's default Embree: the names say so.
  double mrays_per_s = 0.0, embree_robust_mrays_per_s = 0.0, ratio_to_embree_robust = 0.0;
  size_t hit_miss_disagree = 0, prim_disagree = 0, ties = 0;
  size_t raylab_wrong = 0, embree_wrong = 0, occlusion_disagree = 0;
  double max_rel_t_err = 0.0;
  bool watertight_test = false;  // uses the watertight triangle test (leaks fail the run)
  bool counts = true;            // failures count for the exit code (not for embree or tri=mt rows)
  // The reference was timed on every ray of the scenario and released before
  // this structure's build (no room for both): its speed on the traced
  // subset is that rate, not a back-to-back timing.
  bool reference_timed_first = false;
  size_t leak_rays = 0, leaks = 0;
  double leaks_per_million() const { return leak_rays ? 1e6 * static_cast<double>(leaks) / leak_rays : 0.0; }

  // A failure that makes `raylab stress` exit 1.
  bool failed() const {
    return counts && (raylab_wrong > 0 || occlusion_disagree > 0 || (watertight_test && leaks > 0));
  }
};

struct StressOptions {
  std::vector<std::string> scenarios;  // names (expanded); empty = all
  double ray_scale = 1.0;
  uint64_t seed = 1;
  int threads = 0;                      // 0 = all cores
  double time_budget_s = 2.0;           // per scenario x accelerator trace; slower ones trace a subset
  double slow_ratio = 0.05;             // below this ratio to robust Embree a method is reported as slow
  std::string reference = "embree:robust=1";
  bool add_variants = true;             // watertight scenarios: also tri=mt variants and embree robust
  // The scene of the scenarios built on one (make_stress_scenario); empty = the Cornell box.
  std::string scene;
  // Memory (checks/memory_guard.h): a structure that fits only without the
  // reference gets the reference timed on every ray first and released
  // (StressRecord::reference_timed_first); one that does not fit at all is
  // skipped (on_skip); a reference that does not fit throws MemoryShortage
  // (the records before it were passed to `progress`). 0 = no check.
  double memory_headroom = kDefaultMemoryHeadroom;
  std::function<void(const StructureSkip&)> on_skip;
  // Interruption and progress (raylab stress): stop is polled before each
  // scenario x accelerator and inside its traces and oracle calls, per chunk
  // of rays (a record interrupted half-way is dropped); on_start sees it
  // before it runs.
  const std::atomic<bool>* stop = nullptr;
  std::function<void(const std::string& scenario, const std::string& accel, size_t scenario_index,
                     size_t scenarios)>
      on_start;
};

// The accelerator specs a scenario runs: the given ones, plus for watertight
// scenarios (when add_variants) each one's variant from the registry: its
// robust mode (embree:robust=1), else its Moller-Trumbore kernel (tri=mt).
std::vector<std::string> stress_specs_for(const StressScenario& sc, const std::vector<std::string>& specs,
                                          const StressOptions& options);

// Runs every scenario against every spec; `progress` (optional) sees each record as it is done.
std::vector<StressRecord> run_stress(const std::vector<std::string>& accel_specs, const StressOptions& options,
                                     const std::function<void(const StressRecord&)>& progress = {});

}  // namespace raylab
