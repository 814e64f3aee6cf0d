#include "tracer/trace.h"

#include <algorithm>
#include <thread>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "base/timer.h"

namespace raylab {

namespace {
constexpr size_t kChunk = 256;  // rays per batch call: large enough to amortise dispatch
// With a stop flag (Ctrl-C), chunks are made short enough to end within
// about this long: the flag is polled between chunks, and brute force over
// 10^5 triangles takes over a millisecond per ray, a third of a second per
// chunk of 256. kProbe rays, timed first, give the structure's speed.
constexpr double kStopLatencyS = 0.02;
constexpr size_t kProbe = 16;  // a multiple of 16: chunks stay aligned to Embree's widest packets
}  // namespace

int hardware_threads() { return std::max(1u, std::thread::hardware_concurrency()); }

PreparedSet prepare_set(const Accelerator& accel, const RaySet& set) {
  PreparedSet p;
  ThreadCpuTimer t;
  p.rays = accel.prepare(set.rays, set.occlusion);
  p.prepare_s = t.seconds();
  return p;
}

void trace_set(const Accelerator& accel, const RaySet& set, int threads, TraceOutput& out, TraversalStats* stats,
               const PreparedRays* prepared, const std::atomic<bool>* stop) {
  const size_t n = set.rays.size();
  if (set.occlusion) out.occluded.resize(n);
  else out.hits.resize(n);
  auto trace_range = [&](size_t b, size_t e, TraversalStats* s) {
    const std::span<const Ray> rays(set.rays.data() + b, e - b);
    if (set.occlusion) accel.occluded_prepared(prepared, b, rays, std::span<uint8_t>(out.occluded.data() + b, e - b), s);
    else accel.intersect_prepared(prepared, b, rays, std::span<Hit>(out.hits.data() + b, e - b), s);
  };
  auto stopped = [&] { return stop && stop->load(std::memory_order_relaxed); };
  // The first kProbe rays, timed, shorten the chunks of a slow structure
  // (only when a stop flag is given; fast structures keep kChunk).
  size_t first = 0, chunk = kChunk;
  TraversalStats probe_stats;
  if (stop && n > kProbe) {
    if (stopped()) return;
    Timer t;
    trace_range(0, kProbe, stats ? &probe_stats : nullptr);
    const double per_ray = t.seconds() / kProbe;
    if (per_ray * kChunk > kStopLatencyS)
      chunk = std::clamp<size_t>(static_cast<size_t>(kStopLatencyS / per_ray) / kProbe * kProbe, kProbe, kChunk);
    first = kProbe;
  }
  const size_t chunks = (n - first + chunk - 1) / chunk;
  std::vector<TraversalStats> per_chunk(stats ? chunks : 0);
  auto trace_chunk = [&](size_t c) {
    if (stopped()) return;
    const size_t b = first + c * chunk;
    trace_range(b, std::min(n, b + chunk), stats ? &per_chunk[c] : nullptr);
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
  if (stats) {
    *stats += probe_stats;
    for (const auto& s : per_chunk) *stats += s;
  }
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

namespace {

// Timed runs of one accelerator on one set: each run traces the set `passes`
// times. One thread: the loop runs on this thread, so its CPU time is the
// trace's cost, immune to waiting for a core on a loaded machine. More
// threads: wall time, since that is what parallel scaling is about.
class TimedRuns {
 public:
  TimedRuns(const Accelerator& accel, const RaySet& set, int threads, const PreparedRays* prepared,
            const std::atomic<bool>* stop)
      : accel_(accel), set_(set), threads_(threads), stop_(stop) {
    prepared_ = prepared;
    if (!prepared_) {
      own_ = prepare_set(accel, set);
      prepared_ = own_.rays.get();
    }
  }
  bool stopped() const { return stop_ && stop_->load(); }

  // Warm-up (caches, page faults, TBB workers), then untimed calibration
  // runs, as Google Benchmark's: the pass count grows until one run lasts
  // min_time_s (the cold first run is slower than the rest, so its time
  // alone would give too few passes).
  void calibrate(double min_time_s) {
    constexpr int kMaxPasses = 1'000'000;
    double run_s = run(1);
    while (min_time_s > 0 && run_s < min_time_s && passes_ < kMaxPasses && !stopped()) {
      const double per_pass = std::max(run_s / passes_, 1e-9);
      const double wanted = std::ceil(1.2 * min_time_s / per_pass);  // a margin over the estimate
      passes_ = static_cast<int>(std::clamp(wanted, passes_ + 1.0, std::min<double>(kMaxPasses, 1000.0 * passes_)));
      run_s = run(passes_);
    }
  }
  // One timed repeat, kept as seconds per trace of the set.
  void repeat() {
    const double s = run(passes_);
    shortest_ = times_.empty() ? s : std::min(shortest_, s);
    times_.push_back(s / passes_);
  }
  TraceTiming timing() const {
    TraceTiming t = summarize_times(times_);
    t.passes = passes_;
    t.repeat_wall_s = shortest_;
    t.prepare_s = own_.prepare_s;
    t.stopped = stopped();
    return t;
  }

 private:
  double run(int passes) {
    ThreadCpuTimer cpu;
    Timer wall;
    for (int p = 0; p < passes && !stopped(); ++p) trace_set(accel_, set_, threads_, out_, nullptr, prepared_, stop_);
    return threads_ <= 1 ? cpu.seconds() : wall.seconds();
  }

  const Accelerator& accel_;
  const RaySet& set_;
  int threads_;
  const std::atomic<bool>* stop_;
  const PreparedRays* prepared_ = nullptr;
  PreparedSet own_;
  TraceOutput out_;
  int passes_ = 1;
  double shortest_ = 0;
  std::vector<double> times_;
};

}  // namespace

TraceTiming time_trace(const Accelerator& accel, const RaySet& set, int threads, int repeats,
                       const PreparedRays* prepared, double min_time_s, const std::atomic<bool>* stop) {
  TimedRuns runs(accel, set, threads, prepared, stop);
  runs.calibrate(min_time_s);
  for (int i = 0; i < std::max(1, repeats) && !runs.stopped(); ++i) runs.repeat();
  return runs.timing();
}

std::pair<TraceTiming, TraceTiming> time_trace_alternating(const Accelerator& a, const PreparedRays* prepared_a,
                                                           const Accelerator& b, const PreparedRays* prepared_b,
                                                           const RaySet& set, int threads, int repeats,
                                                           double min_time_s, const std::atomic<bool>* stop) {
  TimedRuns ra(a, set, threads, prepared_a, stop), rb(b, set, threads, prepared_b, stop);
  rb.calibrate(min_time_s);
  ra.calibrate(min_time_s);
  for (int i = 0; i < std::max(1, repeats) && !ra.stopped(); ++i) {
    rb.repeat();
    ra.repeat();
  }
  return {ra.timing(), rb.timing()};
}

}  // namespace raylab
