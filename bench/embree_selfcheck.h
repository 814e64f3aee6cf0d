#pragma once
// The check that keeps the reference honest (`raylab bench --embree-selfcheck`):
// on the same prepared rays, one process, one thread, thread CPU time, the
// `embree` accelerator as `raylab bench` times it (trace_set over the batch
// interface) against a plain loop of rtcIntersect1 / rtcOccluded1
// (embree_direct_intersect / embree_direct_occluded). Runs alternate between
// the two so drift on a shared machine affects both alike; medians reported.
#include <string>
#include <vector>

#include "bench/ray_sets.h"
#include "scenes/scene.h"

namespace raylab {

struct SelfCheckRow {
  std::string scene, ray_set;
  size_t rays = 0;
  double adapter_mrays_per_s = 0, direct_mrays_per_s = 0;
  double ratio = 0;        // adapter / direct: 1 = no overhead
  bool identical = false;  // adapter answers bit-identical to the direct loop
  double prepare_ms = 0;   // converting the set into Embree's layout (untimed above)
};

// `embree_spec` must be a single-ray `embree` spec (e.g. "embree" or
// "embree:quality=high"). Sets as make_ray_sets makes them.
std::vector<SelfCheckRow> embree_selfcheck(const Scene& scene, const std::vector<std::string>& ray_sets,
                                           const RaySetOptions& options, int repeats,
                                           const std::string& embree_spec = "embree");

// The same on given sets (e.g. from a ray file).
std::vector<SelfCheckRow> embree_selfcheck_sets(const Scene& scene, const std::vector<RaySet>& sets, int repeats,
                                                const std::string& embree_spec = "embree");

std::string format_selfcheck_table(const std::vector<SelfCheckRow>& rows);

}  // namespace raylab
