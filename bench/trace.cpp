#include "bench/trace.h"

#include <algorithm>
#include <thread>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "accel/util/timer.h"

namespace raylab {

namespace {
constexpr size_t kChunk = 256;  // rays per batch call: large enough to amortise dispatch
}

int hardware_threads() { return std::max(1u, std::thread::hardware_concurrency()); }

PreparedSet prepare_set(const Accelerator& accel, const RaySet& set) {
  PreparedSet p;
  ThreadCpuTimer t;
  p.rays = accel.prepare(set.rays, set.occlusion);
  p.prepare_s = t.seconds();
  return p;
}

void trace_set(const Accelerator& accel, const RaySet& set, int threads, TraceOutput& out, TraversalStats* stats,
               const PreparedRays* prepared) {
  const size_t n = set.rays.size();
  if (set.occlusion) out.occluded.resize(n);
  else out.hits.resize(n);
  const size_t chunks = (n + kChunk - 1) / kChunk;
  std::vector<TraversalStats> per_chunk(stats ? chunks : 0);
  auto trace_chunk = [&](size_t c) {
    const size_t b = c * kChunk, e = std::min(n, b + kChunk);
    const std::span<const Ray> rays(set.rays.data() + b, e - b);
    TraversalStats* s = stats ? &per_chunk[c] : nullptr;
    if (set.occlusion) accel.occluded_prepared(prepared, b, rays, std::span<uint8_t>(out.occluded.data() + b, e - b), s);
    else accel.intersect_prepared(prepared, b, rays, std::span<Hit>(out.hits.data() + b, e - b), s);
  };
  if (threads <= 1) {
    // One thread: a plain loop, no scheduler between the structure and the timer.
    for (size_t c = 0; c < chunks; ++c) trace_chunk(c);
  } else {
    tbb::task_arena arena(threads);
    arena.execute([&] {
      tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t c = r.begin(); c < r.end(); ++c) trace_chunk(c);
      });
    });
  }
  if (stats)
    for (const auto& s : per_chunk) *stats += s;
}

TraceTiming summarize_times(std::vector<double> times) {
  TraceTiming timing;
  if (times.empty()) return timing;
  timing.repeat_s = times;  // in run order, for significance tests between runs (raylab compare)
  std::sort(times.begin(), times.end());
  timing.min_s = times.front();
  timing.max_s = times.back();
  const size_t m = times.size();
  timing.median_s = m % 2 ? times[m / 2] : 0.5 * (times[m / 2 - 1] + times[m / 2]);
  return timing;
}

TraceTiming time_trace(const Accelerator& accel, const RaySet& set, int threads, int repeats,
                       const PreparedRays* prepared) {
  PreparedSet own;
  if (!prepared) {
    own = prepare_set(accel, set);
    prepared = own.rays.get();
  }
  TraceOutput out;
  trace_set(accel, set, threads, out, nullptr, prepared);  // warm-up: caches, page faults, TBB workers
  std::vector<double> times;
  // One thread: the loop runs on this thread, so its CPU time is the trace's
  // cost, immune to waiting for a core on a loaded machine. More threads:
  // wall time, since that is what parallel scaling is about.
  for (int i = 0; i < std::max(1, repeats); ++i) {
    if (threads <= 1) {
      ThreadCpuTimer t;
      trace_set(accel, set, 1, out, nullptr, prepared);
      times.push_back(t.seconds());
    } else {
      Timer t;
      trace_set(accel, set, threads, out, nullptr, prepared);
      times.push_back(t.seconds());
    }
  }
  TraceTiming timing = summarize_times(std::move(times));
  timing.prepare_s = own.prepare_s;
  return timing;
}

}  // namespace raylab
