#pragma once
// `raylab verify`: trace the same rays with Embree (robust mode) and each
// accelerator and count disagreements; every disagreement is referred to the
// double-precision oracle, which decides who was wrong.
#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "tracer/ray_sets.h"
#include "scenes/scene.h"

namespace raylab {

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

  bool failed() const { return raylab_wrong > 0 || occlusion_disagree > 0; }
};

struct VerifyOptions {
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
  // Called with each record as soon as it is finished (raylab verify prints it).
  std::function<void(const VerifyRecord& record)> on_record;
};

std::vector<VerifyRecord> verify_accelerators(const Scene& scene, const std::vector<std::string>& accel_specs,
                                              const VerifyOptions& options);

}  // namespace raylab
