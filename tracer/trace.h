#pragma once
// Tracing a ray set with an accelerator on a given number of threads, and
// timing it: the batch interface is called on chunks of rays, from a TBB
// parallel loop inside an arena of exactly `threads` threads (or a plain
// loop on the calling thread for one thread).
//
// Timed = traversal only: a structure's per-set preparation (its own ray
// layout, see Accelerator::prepare) is done once before timing and reported
// on its own (prepare_s), never inside the timed runs.
#include <atomic>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "accel/accelerator.h"
#include "tracer/ray_sets.h"

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
// structure traces its own layout. `stop` (Ctrl-C) is polled before every
// chunk of rays: once it is set the remaining chunks are skipped and `out`
// is incomplete (the caller checks the flag and discards it). With a stop
// flag a slow structure's chunks are shortened (its speed timed on the first
// rays) to last about 20 ms, so a long trace ends within that of Ctrl-C.
void trace_set(const Accelerator& accel, const RaySet& set, int threads, TraceOutput& out,
               TraversalStats* stats = nullptr, const PreparedRays* prepared = nullptr,
               const std::atomic<bool>* stop = nullptr);

struct TraceTiming {
  // Seconds per trace of the whole set: each timed repeat traced it
  // `passes` times and is stored divided by `passes`.
  double median_s = 0, min_s = 0, max_s = 0;
  std::vector<double> repeat_s;  // every timed repeat, in run order
  int passes = 1;                // traces of the set per timed repeat (min_time_s)
  double repeat_wall_s = 0;      // the shortest timed repeat as measured (passes x one trace)
  double prepare_s = 0;  // preparation (untimed in median/min/max); 0 when `prepared` was given
  bool stopped = false;  // `stop` was set: the figures are incomplete
  double mrays_per_s(size_t rays) const { return median_s > 0 ? rays / median_s * 1e-6 : 0.0; }
};

// Prepares the set (unless `prepared` is given), then one warm-up run and
// `repeats` timed runs of the traversal alone. A timed repeat traces the set
// as many times as it takes to last at least `min_time_s` (as Google
// Benchmark's --benchmark_min_time; the warm-up's time sets the count), so
// short sets are not timed at the clock's and the scheduler's granularity.
TraceTiming time_trace(const Accelerator& accel, const RaySet& set, int threads, int repeats,
                       const PreparedRays* prepared = nullptr, double min_time_s = 0.0,
                       const std::atomic<bool>* stop = nullptr);

// Two accelerators timed in alternation on the same set (b's repeat, then
// a's, `repeats` times, after each one's warm-up and calibration), so that
// repeat i of one and repeat i of the other saw the machine in the same
// state: their ratio cancels load that changes over seconds, which timing
// one after the other does not (bench times each structure against Embree
// this way). Returns (a's timing, b's timing).
std::pair<TraceTiming, TraceTiming> time_trace_alternating(const Accelerator& a, const PreparedRays* prepared_a,
                                                           const Accelerator& b, const PreparedRays* prepared_b,
                                                           const RaySet& set, int threads, int repeats,
                                                           double min_time_s = 0.0,
                                                           const std::atomic<bool>* stop = nullptr);

// Median, min and max of a list of run times.
TraceTiming summarize_times(std::vector<double> times);

int hardware_threads();

}  // namespace raylab
