#pragma once
// Tracing a ray set with an accelerator on a given number of threads, and
// timing it: the batch interface is called on chunks of rays, from a TBB
// parallel loop inside an arena of exactly `threads` threads (or a plain
// loop on the calling thread for one thread).
//
// Timed = traversal only: a structure's per-set preparation (its own ray
// layout, see Accelerator::prepare) is done once before timing and reported
// on its own (prepare_s), never inside the timed runs.
#include <cstdint>
#include <memory>
#include <vector>

#include "accel/accelerator.h"
#include "bench/ray_sets.h"

namespace raylab {

struct TraceOutput {
  std::vector<Hit> hits;          // closest-hit sets
  std::vector<uint8_t> occluded;  // occlusion sets
};

// A structure's prepared form of a set (null when it has none) and the
// thread CPU time the preparation took.
struct PreparedSet {
  std::unique_ptr<PreparedRays> rays;
  double prepare_s = 0;
};
PreparedSet prepare_set(const Accelerator& accel, const RaySet& set);

// Traces once; when stats is non-null runs the instrumented kernels. With
// `prepared` (from prepare_set on the same accelerator and set) the
// structure traces its own layout.
void trace_set(const Accelerator& accel, const RaySet& set, int threads, TraceOutput& out,
               TraversalStats* stats = nullptr, const PreparedRays* prepared = nullptr);

struct TraceTiming {
  double median_s = 0, min_s = 0, max_s = 0;
  std::vector<double> repeat_s;  // every timed repeat, in run order
  double prepare_s = 0;  // preparation (untimed in median/min/max); 0 when `prepared` was given
  double mrays_per_s(size_t rays) const { return median_s > 0 ? rays / median_s * 1e-6 : 0.0; }
};

// Prepares the set (unless `prepared` is given), then one warm-up run and
// `repeats` timed runs of the traversal alone.
TraceTiming time_trace(const Accelerator& accel, const RaySet& set, int threads, int repeats,
                       const PreparedRays* prepared = nullptr);

// Median, min and max of a list of run times.
TraceTiming summarize_times(std::vector<double> times);

int hardware_threads();

}  // namespace raylab
