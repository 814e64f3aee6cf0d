#pragma once
// The timing path of `raylab bench`: build every accelerator on the scene,
// trace the same ray sets with each (Embree always included, in the same
// process), median of repeats, ratios to Embree from this run.
#include <atomic>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "accel/accelerator.h"
#include "checks/structure_skip.h"
#include "tracer/ray_sets.h"
#include "scenes/scene.h"

namespace raylab {

// The default minimum time per timed repeat (BenchOptions::min_time_s).
inline constexpr double kDefaultMinTimeS = 0.05;
// A timed repeat shorter than this is named in a warning (bench_short_repeat_warning).
inline constexpr double kShortRepeatS = 0.01;

struct BenchOptions {
  std::vector<std::string> ray_sets = {"primary", "random"};
  int width = 512, height = 512;  // primary rays
  size_t random_rays = 262144;
  std::vector<int> threads = {1};
  int repeats = 5;
  // Each timed repeat traces the set as many times as it takes to last at
  // least this long (Google Benchmark's --benchmark_min_time): a set traced
  // in about a millisecond is otherwise timed at the scheduler's granularity
  // and its repeats scatter by tens of percent. 0 = one trace per repeat.
  double min_time_s = kDefaultMinTimeS;
  int build_repeats = 1;
  uint64_t seed = 1;
  bool instrumented = true;  // one extra instrumented pass for per-ray counters
  std::string embree_spec = "embree";
  // Accelerators named "brute" are skipped on scenes with more triangles than
  // this (their trace time grows with triangles x rays); 0 = never skip.
  size_t brute_max_triangles = 0;
  // Polled between cells and inside their traces, per chunk of rays: when it
  // becomes true run_bench returns the records finished so far (Ctrl-C in
  // `raylab bench`); the cell it was in is dropped.
  const std::atomic<bool>* stop = nullptr;
  // When non-empty, these sets are traced instead of generating ray_sets
  // (`raylab bench --ray-file`).
  std::vector<RaySet> given_sets;
  // Before each build: skip structures whose estimated peak memory
  // (checks/memory_guard.h) exceeds this fraction of the memory still
  // available; 0 = never skip. When a structure only
  // fits without the Embree reference resident, Embree is timed on every ray
  // set first and released (records say so: extra embree_timed_first = 1).
  double memory_headroom = 0.95;
};

// A structure left out of a scene, with the reason ("needs ~31.2 GiB by its
// estimate, 20.1 GiB available"): the type verify uses too.
using BenchSkip = StructureSkip;

struct BenchRecord {
  std::string scene, accel, ray_set;
  size_t triangles = 0, rays = 0;
  int threads = 1;
  double build_ms = 0;
  size_t bytes = 0;
  double mrays_per_s = 0, mrays_min = 0, mrays_max = 0;
  double prepare_ms = 0;  // the structure's per-set preparation (not part of the timed traversal)
  double embree_mrays_per_s = 0, ratio_to_embree = 0;  // the reference: single-ray `embree`
  // The fastest Embree mode (any `embree...` spec) measured in the same run
  // for this scene, ray set and thread count; ratio_to_best_embree =
  // ratio_to_embree / (that mode's ratio_to_embree), so both come from
  // back-to-back timings against the same reference.
  std::string best_embree;
  double best_embree_mrays_per_s = 0, ratio_to_best_embree = 0;
  double embree_agreement = 1.0;  // fraction of rays answered like Embree (ties count as agreement)
  double nodes_per_ray = 0, tris_per_ray = 0;  // NaN: not counted (Embree has no traversal counters)
  // Havran's counts per ray (accel/core/hit_recorder.h); NaN as above.
  double steps_per_ray = 0, leaves_per_ray = 0, empty_leaves_per_ray = 0;
  double sah_cost = 0;                          // NaN: not reported by the structure
  size_t nodes = 0, leaves = 0;                 // 0 with has_tree false: not reported (Embree)
  int max_depth = 0;
  bool has_tree = true;
  std::vector<double> trace_s;  // seconds per trace of the set in each timed repeat, in run order (raylab compare's test)
  // Embree's repeats in the same cell, timed in alternation with trace_s
  // (repeat i of each saw the machine alike): their ratio is the per-repeat
  // ratio to Embree.
  std::vector<double> embree_trace_s;
  int trace_passes = 1;         // traces of the set per timed repeat (--min-time)
  double shortest_repeat_s = 0; // the shortest timed repeat as measured (trace_passes traces)
  std::map<std::string, double> extra;  // BuildStats::extra (structure-specific figures)
  // Resident set of the process (from the OS) just before this structure's
  // build, and its peak from then until this record (build, ray sets and
  // traces; the scene, and Embree unless released, are part of both).
  size_t rss_before_build_bytes = 0, rss_peak_bytes = 0;

  nlohmann::json to_json() const;
};

using BenchProgress = std::function<void(const std::string& message)>;
using BenchRecordSink = std::function<void(const BenchRecord& record)>;
using BenchSkipSink = std::function<void(const BenchSkip& skip)>;

// Records in the order accelerator x ray set x threads, Embree modes first;
// on_record (when set) is called as soon as each cell is finished, so callers
// can save them. The best-Embree fields are known only when every Embree
// mode ran: they are filled in the returned records (and in those passed to
// on_record after the last Embree mode).
std::vector<BenchRecord> run_bench(const Scene& scene, const std::vector<std::string>& accel_specs,
                                   const BenchOptions& options, const BenchProgress& progress = {},
                                   const BenchRecordSink& on_record = {}, const BenchSkipSink& on_skip = {});

// The specs run_bench times on this scene (brute dropped above brute_max_triangles).
std::vector<std::string> bench_specs_for_scene(const std::vector<std::string>& accel_specs, size_t triangles,
                                               const BenchOptions& options);

// CSV with one row per record (the flat fields of to_json, extra omitted).
std::string bench_csv(const std::vector<BenchRecord>& records);

// Non-empty when a depth-capped build (k-d tree: extra "max_depth_limit")
// reached its cap: leaves may then hold more triangles than the cost model wanted.
std::string depth_cap_warning(const BuildStats& stats);

// Fixed-width table for the terminal. The best-Embree columns are shown
// only when another Embree mode than the reference ran (else they repeat
// the ratio to Embree).
std::string format_bench_table(const std::vector<BenchRecord>& records);

// The noise floor of the ratios: single-ray Embree is timed back to back with
// every structure, so each (scene, ray set, threads) has one Embree timing
// per cell. Their spread ((max - min) / median) is what the ratios cannot
// resolve. One line per (scene, ray set, threads) with two or more timings.
struct EmbreeNoise {
  std::string scene, ray_set;
  int threads = 1;
  size_t timings = 0;
  double min_mrays = 0, median_mrays = 0, max_mrays = 0;
  double spread_pct() const { return median_mrays > 0 ? 100.0 * (max_mrays - min_mrays) / median_mrays : 0.0; }
};
std::vector<EmbreeNoise> embree_noise(const std::vector<BenchRecord>& records);
std::string format_embree_noise(const std::vector<EmbreeNoise>& noise);

// Non-empty when some cells' timed repeats lasted under kShortRepeatS: names
// them (and the remedy, --min-time).
std::string bench_short_repeat_warning(const std::vector<BenchRecord>& records);

// One line per accelerator: SAH cost, nodes, leaves, depth, bytes per
// triangle and its structure-specific build figures.
std::string format_build_summary(const std::vector<BenchRecord>& records);

}  // namespace raylab
