#pragma once
// Tracing a ray set with an accelerator on a given number of threads, and
// timing it: the batch interface is called on chunks of rays from a TBB
// parallel loop inside an arena of exactly `threads` threads.
#include <cstdint>
#include <vector>

#include "accel/accelerator.h"
#include "bench/ray_sets.h"

namespace raylab {

struct TraceOutput {
  std::vector<Hit> hits;          // closest-hit sets
  std::vector<uint8_t> occluded;  // occlusion sets
};

// Traces once; when stats is non-null runs the instrumented kernels.
void trace_set(const Accelerator& accel, const RaySet& set, int threads, TraceOutput& out,
               TraversalStats* stats = nullptr);

struct TraceTiming {
  double median_s = 0, min_s = 0, max_s = 0;
  std::vector<double> repeat_s;  // every timed repeat, in run order
  double mrays_per_s(size_t rays) const { return median_s > 0 ? rays / median_s * 1e-6 : 0.0; }
};

// One warm-up run, then `repeats` timed runs.
TraceTiming time_trace(const Accelerator& accel, const RaySet& set, int threads, int repeats);

int hardware_threads();

}  // namespace raylab
