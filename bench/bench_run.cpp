#include "bench/bench_run.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <new>
#include <tuple>

#include <fmt/format.h>

#include "accel/registry.h"
#include "base/timer.h"
#include "checks/memory_guard.h"
#include "checks/process_memory.h"
#include "checks/classify.h"
#include "tracer/ray_sets.h"
#include "tracer/trace.h"

namespace raylab {

// The fields written under their own names (docs/json-reports.md); to_json
// adds the derived and the possibly-null ones.
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(BenchRecord, scene, triangles, accel, ray_set, threads, rays, build_ms, bytes,
                                   mrays_per_s, mrays_min, mrays_max, prepare_ms, embree_mrays_per_s, ratio_to_embree,
                                   best_embree, best_embree_mrays_per_s, ratio_to_best_embree, embree_agreement, trace_s,
                                   embree_trace_s, trace_passes, shortest_repeat_s, extra, rss_before_build_bytes, rss_peak_bytes)

nlohmann::json BenchRecord::to_json() const {
  nlohmann::json j = *this;
  j["bytes_per_triangle"] = triangles ? static_cast<double>(bytes) / triangles : 0.0;
  // null where a figure does not apply.
  auto number_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  auto tree_figure_or_null = [this](auto v) { return has_tree ? nlohmann::json(v) : nlohmann::json(nullptr); };
  j["nodes_per_ray"] = number_or_null(nodes_per_ray);
  j["tris_per_ray"] = number_or_null(tris_per_ray);
  j["steps_per_ray"] = number_or_null(steps_per_ray);
  j["leaves_per_ray"] = number_or_null(leaves_per_ray);
  j["empty_leaves_per_ray"] = number_or_null(empty_leaves_per_ray);
  j["sah_cost"] = number_or_null(sah_cost);
  j["nodes"] = tree_figure_or_null(nodes);
  j["leaves"] = tree_figure_or_null(leaves);
  j["max_depth"] = tree_figure_or_null(max_depth);
  return j;
}

namespace {

double agreement(const RaySet& set, const TraceOutput& a, const TraceOutput& e) {
  if (set.rays.empty()) return 1.0;
  size_t same = 0;
  for (size_t i = 0; i < set.rays.size(); ++i) {
    if (set.occlusion) {
      same += a.occluded[i] == e.occluded[i];
    } else {
      // Agreement as verify and stress screen it (checks/classify.h): the
      // same answer, or a tie.
      same += screen_closest(a.hits[i], e.hits[i]) != Screen::Disagree;
    }
  }
  return static_cast<double>(same) / static_cast<double>(set.rays.size());
}

struct Built {
  std::string spec;
  std::unique_ptr<Accelerator> accel;
  BuildStats stats;
};

Built build_accel(const std::string& spec, const Scene& scene, int repeats) {
  Built b{spec, nullptr, {}};
  std::vector<double> times;
  for (int i = 0; i < std::max(1, repeats); ++i) {
    b.accel = make_accelerator(spec);
    b.stats = b.accel->build(scene.mesh);
    times.push_back(b.stats.build_ms);
  }
  std::sort(times.begin(), times.end());
  b.stats.build_ms = times[times.size() / 2];
  b.spec = b.accel->spec();
  return b;
}

// A structure fits when its estimated peak is below the headroom share of
// what the OS can still give this process (a Slurm job's cgroup included):
// the guard every command shares (checks/memory_guard.h).
struct MemoryCheck {
  const TriangleMesh& mesh;
  MemoryGuard guard;

  bool fits(const std::string& spec, size_t extra_room) {
    MemoryStep step = structure_step(spec, mesh);
    if (is_reference_spec(spec)) step.what = "the Embree reference";
    return guard.fits(step, extra_room);
  }
  std::string needs() const { return guard.shortage(); }
  size_t estimate() const { return guard.last_estimate(); }
  size_t available() const { return guard.last_available(); }
};

// The fastest Embree mode so far per (set, threads): its ratio to the
// reference, its spec and speed; every record's best-mode figures.
class BestEmbreeModes {
 public:
  void note(const BenchRecord& r, size_t set, bool embree_mode, const std::string& reference) {
    const std::pair<size_t, int> key{set, r.threads};
    // The reference counts as measured (ratio 1) even when not in the list.
    if (!best_.count(key)) best_[key] = Mode{1.0, reference, r.embree_mrays_per_s};
    Mode& cur = best_[key];
    if (embree_mode && r.ratio_to_embree > cur.ratio) cur = Mode{r.ratio_to_embree, r.accel, r.mrays_per_s};
  }
  void fill(BenchRecord& r, size_t set) const {
    const auto it = best_.find({set, r.threads});
    if (it == best_.end() || !(it->second.ratio > 0)) return;
    r.best_embree = it->second.spec;
    r.best_embree_mrays_per_s = it->second.mrays_per_s;
    r.ratio_to_best_embree = r.ratio_to_embree / it->second.ratio;
  }

 private:
  struct Mode {
    double ratio = 0.0;
    std::string spec;
    double mrays_per_s = 0.0;
  };
  std::map<std::pair<size_t, int>, Mode> best_;
};

// The accelerator's and the reference's timing of one (set, threads) cell.
struct TimedPair {
  TraceTiming accel, embree;
};

// One record of the matrix: the structure's build figures, its timing
// against the reference's, the agreement and the per-ray counters.
BenchRecord make_record(const std::string& scene, size_t triangles, const Built& b, const RaySet& set, int threads,
                        const PreparedSet& prep, const TimedPair& timing, double agree, const TraversalStats& ts) {
  BenchRecord r;
  r.scene = scene;
  r.triangles = triangles;
  r.accel = b.spec;
  r.ray_set = set.name;
  r.threads = threads;
  r.rays = set.rays.size();
  r.build_ms = b.stats.build_ms;
  r.bytes = b.stats.bytes;
  r.prepare_ms = prep.prepare_s * 1e3;
  r.mrays_per_s = timing.accel.mrays_per_s(r.rays);
  r.mrays_min = timing.accel.max_s > 0 ? r.rays / timing.accel.max_s * 1e-6 : 0;
  r.mrays_max = timing.accel.min_s > 0 ? r.rays / timing.accel.min_s * 1e-6 : 0;
  r.embree_mrays_per_s = timing.embree.mrays_per_s(r.rays);
  r.ratio_to_embree = r.embree_mrays_per_s > 0 ? r.mrays_per_s / r.embree_mrays_per_s : 0;
  r.embree_agreement = agree;
  r.nodes_per_ray = r.tris_per_ray = std::numeric_limits<double>::quiet_NaN();
  r.steps_per_ray = r.leaves_per_ray = r.empty_leaves_per_ray = r.nodes_per_ray;
  // A structure without counters (Embree) leaves them at zero: n/a, not 0.
  if (ts.rays && (ts.nodes_visited > 0 || ts.triangle_tests > 0 || ts.leaves > 0)) {
    const auto per_ray = [&](uint64_t n) { return static_cast<double>(n) / static_cast<double>(ts.rays); };
    r.nodes_per_ray = per_ray(ts.nodes_visited);
    r.tris_per_ray = per_ray(ts.triangle_tests);
    r.steps_per_ray = per_ray(ts.steps);
    r.leaves_per_ray = per_ray(ts.leaves);
    r.empty_leaves_per_ray = per_ray(ts.empty_leaves);
  }
  r.sah_cost = b.stats.sah_cost;
  r.nodes = b.stats.nodes;
  r.leaves = b.stats.leaves;
  r.max_depth = b.stats.max_depth;
  r.has_tree = b.stats.nodes > 0 || b.stats.leaves > 0;
  r.trace_s = timing.accel.repeat_s;
  r.embree_trace_s = timing.embree.repeat_s;
  r.trace_passes = timing.accel.passes;
  r.shortest_repeat_s = timing.accel.repeat_wall_s;
  r.extra = b.stats.extra;
  return r;
}

// The given ray sets, or those named in the options made on `reference`.
std::vector<RaySet> bench_ray_sets(const Scene& scene, const BenchOptions& o, const Accelerator& reference) {
  if (!o.given_sets.empty()) return o.given_sets;
  RaySetOptions rso;
  rso.width = o.width;
  rso.height = o.height;
  rso.random_count = o.random_rays;
  rso.seed = o.seed;
  return make_ray_sets(scene, o.ray_sets, reference, rso);
}

}  // namespace

std::vector<std::string> bench_specs_for_scene(const std::vector<std::string>& accel_specs, size_t triangles,
                                               const BenchOptions& o) {
  std::vector<std::string> out;
  // The reference's modes (Embree) first, so the best of them is known for
  // the other records.
  std::vector<std::string> ordered;
  for (const auto& spec : accel_specs)
    if (is_reference_spec(spec)) ordered.push_back(spec);
  for (const auto& spec : accel_specs)
    if (!is_reference_spec(spec)) ordered.push_back(spec);
  for (const auto& spec : ordered) {
    // Structures whose cost grows with rays x triangles skip large scenes.
    const bool quadratic = accelerator_info(Spec::parse(spec).name).caps.quadratic;
    if (quadratic && o.brute_max_triangles > 0 && triangles > o.brute_max_triangles) continue;
    out.push_back(spec);
  }
  return out;
}

std::vector<BenchRecord> run_bench(const Scene& scene, const std::vector<std::string>& all_specs,
                                   const BenchOptions& o, const BenchProgress& progress,
                                   const BenchRecordSink& on_record, const BenchSkipSink& on_skip) {
  auto say = [&](const std::string& m) {
    if (progress) progress(m);
  };
  auto stopped = [&] { return o.stop && o.stop->load(); };
  const size_t triangles = scene.num_triangles();
  const std::vector<std::string> accel_specs = bench_specs_for_scene(all_specs, triangles, o);
  MemoryCheck mem{scene.mesh, MemoryGuard(o.memory_headroom)};
  auto skip = [&](const std::string& spec, const std::string& reason, size_t estimate, size_t available) {
    std::fprintf(stderr, "bench: %s on %s: skipped: %s\n", spec.c_str(), scene.name.c_str(), reason.c_str());
    if (on_skip) on_skip(BenchSkip{scene.name, spec, reason, triangles, estimate, available});
  };
  if (!mem.fits(o.embree_spec, 0)) {
    // Without the reference nothing can be timed: every structure is skipped.
    const std::string reason = mem.needs();
    for (const auto& spec : accel_specs) skip(spec, reason, mem.estimate(), mem.available());
    return {};
  }
  say("building embree (reference)");
  reset_peak_resident();
  const size_t rss_before_embree = resident_bytes();
  Built embree = build_accel(o.embree_spec, scene, o.build_repeats);
  const size_t embree_resident = resident_bytes() > rss_before_embree ? resident_bytes() - rss_before_embree : 0;

  const std::vector<RaySet> sets = bench_ray_sets(scene, o, *embree.accel);

  // The reference's prepared sets (made once), its answers for agreement.
  std::vector<PreparedSet> embree_prepared(sets.size());
  std::vector<TraceOutput> embree_out(sets.size());
  for (size_t s = 0; s < sets.size(); ++s) {
    embree_prepared[s] = prepare_set(*embree.accel, sets[s]);
    trace_set(*embree.accel, sets[s], 1, embree_out[s], nullptr, embree_prepared[s].rays.get(), o.stop);
  }
  // Filled only when Embree is released to make room (then timed once, first).
  std::map<std::pair<size_t, int>, TraceTiming> embree_timed_first;
  auto embree_timing = [&](size_t s, int threads) {
    const auto it = embree_timed_first.find({s, threads});
    return it != embree_timed_first.end()
               ? it->second
               : time_trace(*embree.accel, sets[s], threads, o.repeats, embree_prepared[s].rays.get(), o.min_time_s,
                            o.stop);
  };

  std::vector<BenchRecord> records;
  BestEmbreeModes best;
  size_t embree_modes_left = 0;
  for (const auto& spec : accel_specs) embree_modes_left += is_reference_spec(spec);
  std::vector<size_t> record_set;  // set index of each record
  for (const auto& spec : accel_specs) {
    if (stopped()) break;
    const bool is_embree = spec == embree.spec;
    if (is_embree && !embree.accel) {
      skip(spec, "the Embree reference was released to make room for a larger structure", 0, 0);
      continue;
    }
    size_t rss_before_build = rss_before_embree;
    if (!is_embree) {
      if (!mem.fits(spec, 0)) {
        const std::string alone = mem.needs();
        if (embree.accel && mem.fits(spec, embree_resident)) {
          // Fits once Embree's memory is returned: time Embree on every
          // (set, threads) now, keep its answers, release it.
          for (size_t s = 0; s < sets.size(); ++s)
            for (int threads : o.threads) embree_timed_first[{s, threads}] = embree_timing(s, threads);
          embree.accel.reset();
          std::fprintf(stderr, "bench: %s on %s: %s; fits without Embree: Embree timed first and released\n",
                       spec.c_str(), scene.name.c_str(), alone.c_str());
        } else {
          skip(spec, mem.needs(), mem.estimate(), mem.available());
          continue;
        }
      }
      reset_peak_resident();
      rss_before_build = resident_bytes();
    }
    say(fmt::format("building {}", spec));
    Built b;
    try {
      b = is_embree ? Built{embree.spec, nullptr, embree.stats} : build_accel(spec, scene, o.build_repeats);
    } catch (const std::bad_alloc&) {
      // The estimate was too low: still a record of why, not a crash.
      skip(spec, fmt::format("out of memory while building (estimate was ~{})", format_bytes(static_cast<double>(mem.estimate()))),
           mem.estimate(), available_memory_bytes());
      continue;
    } catch (const std::exception& e) {
      // A structure that cannot be built on this scene (e.g. a grid whose memory
      // budget cannot hold 10^8 triangles' references): a record of why, and the
      // rest of the matrix still runs. Specs were validated before the scene loaded.
      skip(spec, fmt::format("build failed: {}", e.what()), mem.estimate(), available_memory_bytes());
      continue;
    }
    const Accelerator& accel = b.accel ? *b.accel : *embree.accel;
    const bool is_reference = &accel == embree.accel.get();
    const bool embree_mode = is_reference_spec(b.spec);
    for (size_t s = 0; s < sets.size() && !stopped(); ++s) {
      const RaySet& set = sets[s];
      say(fmt::format("preparing {} {} rays for {}", set.rays.size(), set.name, b.spec));
      PreparedSet own;
      if (!is_reference) own = prepare_set(accel, set);
      const PreparedSet& prep = is_reference ? embree_prepared[s] : own;
      TraceOutput out;
      trace_set(accel, set, 1, out, nullptr, prep.rays.get(), o.stop);
      if (stopped()) break;
      const double agree = agreement(set, out, embree_out[s]);
      TraversalStats ts;
      if (o.instrumented) trace_set(accel, set, 1, out, &ts, prep.rays.get(), o.stop);
      for (int threads : o.threads) {
        if (stopped()) break;
        say(fmt::format("tracing {} {} rays with {} ({} thread{})", set.rays.size(), set.name, b.spec, threads,
                        threads == 1 ? "" : "s"));
        // Embree and the accelerator timed in alternation, repeat by repeat,
        // so load that changes over seconds on this shared machine affects
        // both alike, both on their prepared rays (unless Embree had to go
        // first to make room: then one after the other).
        TraceTiming t, et;
        if (is_reference) {
          t = et = embree_timing(s, threads);
        } else if (embree_timed_first.empty()) {
          std::tie(t, et) = time_trace_alternating(accel, prep.rays.get(), *embree.accel, embree_prepared[s].rays.get(),
                                                   set, threads, o.repeats, o.min_time_s, o.stop);
        } else {
          et = embree_timing(s, threads);
          t = time_trace(accel, set, threads, o.repeats, prep.rays.get(), o.min_time_s, o.stop);
        }
        if (stopped()) break;  // interrupted inside the cell: its timings are partial, it is not kept
        BenchRecord r = make_record(scene.name, triangles, b, set, threads, prep, TimedPair{t, et}, agree, ts);
        if (!embree_timed_first.empty()) r.extra["embree_timed_first"] = 1;
        r.rss_before_build_bytes = rss_before_build;
        r.rss_peak_bytes = peak_resident_bytes();
        best.note(r, s, embree_mode, embree.spec);
        // Embree modes get their best-mode figures once all of them ran (below).
        if (!embree_mode || embree_modes_left == 1) best.fill(r, s);
        records.push_back(r);
        record_set.push_back(s);
        if (on_record) on_record(r);
      }
    }
    if (embree_mode && embree_modes_left > 0) --embree_modes_left;
  }
  for (size_t i = 0; i < records.size(); ++i) best.fill(records[i], record_set[i]);
  return records;
}

std::string bench_csv(const std::vector<BenchRecord>& records) {
  static const char* const kColumns[] = {"scene",       "triangles",   "accel",          "ray_set",          "threads",
                                         "rays",        "build_ms",    "bytes",          "bytes_per_triangle",
                                         "mrays_per_s", "mrays_min",   "mrays_max",      "prepare_ms", "embree_mrays_per_s",
                                         "ratio_to_embree", "best_embree", "ratio_to_best_embree", "embree_agreement",
                                         "trace_passes", "shortest_repeat_s", "nodes_per_ray", "tris_per_ray",
                                         "steps_per_ray", "leaves_per_ray", "empty_leaves_per_ray",
                                         "sah_cost",    "nodes",       "leaves",         "max_depth",
                                         "rss_before_build_bytes", "rss_peak_bytes"};
  auto quote = [](const std::string& v) {
    if (v.find_first_of(",\"\n") == std::string::npos) return v;
    std::string q = "\"";
    for (char c : v) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
  };
  std::string s;
  for (const char* c : kColumns) s += std::string(s.empty() ? "" : ",") + c;
  s += "\n";
  for (const auto& r : records) {
    const nlohmann::json j = r.to_json();
    std::string line;
    for (const char* c : kColumns) {
      const auto& v = j.at(c);
      std::string cell;
      if (v.is_string()) cell = quote(v.get<std::string>());
      else if (v.is_null()) cell = "";
      else if (v.is_number_float()) cell = fmt::format("{:.9g}", v.get<double>());
      else cell = v.dump();
      line += std::string(c == kColumns[0] ? "" : ",") + cell;
    }
    s += line + "\n";
  }
  return s;
}

std::string format_bench_table(const std::vector<BenchRecord>& records) {
  // "x embree": to single-ray `embree` timed back to back in the same cell;
  // "x best": to the fastest Embree mode of the run (named in the last
  // column), shown only when another Embree mode ran.
  bool other_modes = false;
  for (const auto& r : records) other_modes |= !r.best_embree.empty() && r.best_embree != "embree";
  std::string s = fmt::format("{:<34} {:<8} {:>3} {:>9} {:>10} {:>8} {:>9} {:>9} {:>8} ", "accel", "rays", "thr",
                              "build ms", "bytes", "prep ms", "Mrays/s", "embree", "x embree");
  if (other_modes) s += fmt::format("{:>8} ", "x best");
  s += fmt::format("{:>8} {:>7} {:>7}{}\n", "agree %", "nodes/r", "tris/r", other_modes ? "  best embree" : "");
  auto per_ray = [](double v) { return std::isfinite(v) ? fmt::format("{:.1f}", v) : std::string("n/a"); };
  for (const auto& r : records) {
    s += fmt::format("{:<34} {:<8} {:>3} {:>9.2f} {:>10} {:>8.2f} {:>9.2f} {:>9.2f} {:>8.3f} ",
                     r.accel.size() > 34 ? r.accel.substr(0, 34) : r.accel, r.ray_set, r.threads, r.build_ms, r.bytes,
                     r.prepare_ms, r.mrays_per_s, r.embree_mrays_per_s, r.ratio_to_embree);
    if (other_modes) s += fmt::format("{:>8.3f} ", r.ratio_to_best_embree);
    s += fmt::format("{:>8.3f} {:>7} {:>7}{}\n", 100.0 * r.embree_agreement, per_ray(r.nodes_per_ray),
                     per_ray(r.tris_per_ray), other_modes ? "  " + r.best_embree : std::string());
  }
  return s;
}

std::vector<EmbreeNoise> embree_noise(const std::vector<BenchRecord>& records) {
  std::map<std::tuple<std::string, std::string, int>, std::vector<double>> speeds;
  std::vector<std::tuple<std::string, std::string, int>> order;
  for (const auto& r : records) {
    if (!(r.embree_mrays_per_s > 0)) continue;
    const auto key = std::make_tuple(r.scene, r.ray_set, r.threads);
    if (!speeds.count(key)) order.push_back(key);
    speeds[key].push_back(r.embree_mrays_per_s);
  }
  std::vector<EmbreeNoise> out;
  for (const auto& key : order) {
    std::vector<double> v = speeds[key];
    if (v.size() < 2) continue;
    std::sort(v.begin(), v.end());
    EmbreeNoise n;
    std::tie(n.scene, n.ray_set, n.threads) = key;
    n.timings = v.size();
    n.min_mrays = v.front();
    n.max_mrays = v.back();
    n.median_mrays = v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
    out.push_back(n);
  }
  return out;
}

std::string format_embree_noise(const std::vector<EmbreeNoise>& noise) {
  if (noise.empty()) return {};
  std::string s =
      "noise floor: single-ray Embree timed in alternation with each structure (median Mrays/s, min - max, "
      "spread = (max - min) / median); ratios closer than the spread are not resolved\n";
  for (const auto& n : noise)
    s += fmt::format("  embree {:<8} t{:<3} {:>3} timings: {:>8.2f} ({:.2f} - {:.2f}), spread {:.1f} %\n", n.ray_set,
                     n.threads, n.timings, n.median_mrays, n.min_mrays, n.max_mrays, n.spread_pct());
  return s;
}

std::string bench_short_repeat_warning(const std::vector<BenchRecord>& records) {
  std::vector<std::string> cells;
  for (const auto& r : records)
    if (r.shortest_repeat_s > 0 && r.shortest_repeat_s < kShortRepeatS)
      cells.push_back(fmt::format("{} {} t{} ({:.2g} ms)", r.accel, r.ray_set, r.threads, 1e3 * r.shortest_repeat_s));
  if (cells.empty()) return {};
  const size_t shown = std::min<size_t>(cells.size(), 8);
  return fmt::format("warning: {} cell{} timed in repeats under {:.0f} ms, where the clock and the scheduler dominate: "
                     "{}{}; raise --min-time (seconds per timed repeat)\n",
                     cells.size(), cells.size() == 1 ? "" : "s", 1e3 * kShortRepeatS,
                     fmt::join(cells.begin(), cells.begin() + static_cast<std::ptrdiff_t>(shown), ", "),
                     cells.size() > shown ? fmt::format(" and {} more", cells.size() - shown) : std::string());
}

std::string depth_cap_warning(const BuildStats& stats) {
  const auto it = stats.extra.find("max_depth_limit");
  if (it == stats.extra.end() || stats.max_depth < static_cast<int>(it->second)) return {};
  return fmt::format("the tree reached its depth cap ({} levels): deeper splits were refused and leaves may be larger "
                     "than the cost model wanted (raise max_depth, up to 64)",
                     static_cast<int>(it->second));
}

std::string format_build_summary(const std::vector<BenchRecord>& records) {
  std::string s;
  std::string last;
  for (const auto& r : records) {
    if (r.accel == last) continue;
    last = r.accel;
    const std::string sah = std::isfinite(r.sah_cost) ? fmt::format("{:.3f}", r.sah_cost) : std::string("n/a");
    s += fmt::format("build {}: {:.2f} ms, {:.1f} bytes/tri, sah {}", r.accel, r.build_ms,
                     r.triangles ? static_cast<double>(r.bytes) / r.triangles : 0.0, sah);
    s += r.has_tree ? fmt::format(", nodes {}, leaves {}, depth {}", r.nodes, r.leaves, r.max_depth)
                    : std::string(", nodes n/a, leaves n/a, depth n/a (not reported by the structure)");
    for (const auto& [k, v] : r.extra) s += fmt::format(", {} {:.4g}", k, v);
    s += "\n";
    BuildStats st;
    st.max_depth = r.max_depth;
    st.extra = r.extra;
    const std::string warning = depth_cap_warning(st);
    if (!warning.empty()) s += fmt::format("warning: {}: {}\n", r.accel, warning);
  }
  return s;
}

}  // namespace raylab
