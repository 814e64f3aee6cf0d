#pragma once
// `raylab verify`: trace the same rays with Embree (robust mode) and each
// accelerator and count disagreements; every disagreement is referred to the
// oracle (exact where double precision cannot decide), which decides who was
// wrong. Memory: the reference's answers are computed and stored, the
// reference is released, then each structure is built, checked and released
// in turn, each step only when its estimate fits (checks/memory_guard.h), so
// the peak is the largest single structure plus the stored rays and answers.
#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "base/hit.h"
#include "checks/memory_guard.h"
#include "checks/structure_skip.h"
#include "tracer/ray_sets.h"
#include "scenes/scene.h"

namespace raylab {

// One disagreement as the oracle judged it: the ray's index in its set, the
// structure's, the reference's and the oracle's answers, and the verdict
// ("raylab wrong", "embree wrong", "both wrong", "tie").
struct JudgedRay {
  size_t ray = 0;
  Hit got, ref;
  bool oracle_hit = false;
  uint32_t oracle_prim = kInvalidPrim;
  double oracle_t = 0;
  std::string verdict;
};

struct VerifyRecord {
  std::string scene, accel, ray_set;
  size_t rays = 0;
  size_t hit_miss_disagree = 0;   // one reports a hit, the other a miss
  size_t prim_disagree = 0;       // different triangles at distances beyond the tie tolerance
  size_t ties = 0;                // different triangles at the same distance, or grazing rays
  size_t raylab_wrong = 0;        // the accelerator disagrees with the oracle
  size_t embree_wrong = 0;        // Embree disagrees with the oracle
  size_t occlusion_disagree = 0;  // the accelerator's any-hit disagrees with its own closest hit
  double max_rel_t_err = 0.0;     // over rays where both hit
  double build_ms = 0.0;
  // The first disagreements the oracle judged (up to VerifyOptions::judged_kept), each with the three answers.
  std::vector<JudgedRay> judged;

  bool failed() const { return raylab_wrong > 0 || occlusion_disagree > 0; }
};

struct VerifyOptions {
  double memory_headroom = kDefaultMemoryHeadroom;  // checks/memory_guard.h; 0 = no check
  size_t judged_kept = 20;                          // VerifyRecord::judged per record
  // Different triangles at the same distance (within kTieTolerance) are a
  // tie without asking the oracle; with judge_ties the oracle judges them
  // too. At 10^8 triangles a triangle is ~3e-4 of the scene wide, so a
  // neighbour the ray does not cross can lie within the tolerance.
  bool judge_ties = false;
  std::vector<std::string> ray_sets = {"primary", "random"};
  size_t rays = 65536;  // per ray set
  uint64_t seed = 1;
  int threads = 0;      // 0 = all cores
  std::string reference = "embree:robust=1";
  // Interruption and progress (raylab verify): stop is polled between
  // records and inside their traces and comparisons, per chunk of rays (a
  // record interrupted half-way is dropped); on_start sees "accel on set" before each, with its index and the total.
  const std::atomic<bool>* stop = nullptr;
  std::function<void(size_t index, size_t total, const std::string& what)> on_start;
  // Each record as soon as it is finished (so the caller can write it), and
  // each structure left out: estimated not to fit (checks/memory_guard.h) or
  // its build failed. A reference or ray sets that do not fit stop the run
  // before anything is built: verify_accelerators throws MemoryShortage.
  std::function<void(const VerifyRecord&)> on_record;
  std::function<void(const StructureSkip&)> on_skip;
};

// One line per judged ray ("  ray 4711: bvh prim 12 t 0.5; reference prim 13 t 0.5; oracle prim 12 t 0.5 -> embree wrong").
std::string format_judged_rays(const std::vector<JudgedRay>& judged);

std::vector<VerifyRecord> verify_accelerators(const Scene& scene, const std::vector<std::string>& accel_specs,
                                              const VerifyOptions& options);

}  // namespace raylab
