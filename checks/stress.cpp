// The runner of `raylab stress` (checks/stress.h).
#include "checks/stress.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include "accel/registry.h"
#include "base/spec.h"
#include "base/timer.h"
#include "checks/classify.h"
#include "checks/oracle.h"
#include "checks/process_memory.h"
#include "checks/scene_oracle.h"
#include "tracer/trace.h"

namespace raylab {

namespace {

// The oracle's answers, computed once per ray of a scenario and shared by
// every accelerator (Embree's own mistakes make every accelerator disagree
// on the same rays).
class TruthCache {
 public:
  TruthCache(const TriangleMesh& mesh, const std::vector<Ray>& rays)
      : oracle_(mesh), rays_(rays), truth_(rays.size()), known_(rays.size(), 0) {}

  // Computes the missing answers for `ids` in parallel (call outside parallel loops over the same ids).
  // Once `stop` is set nothing more is computed or marked known.
  void ensure(const std::vector<uint32_t>& ids, const std::atomic<bool>* stop) {
    std::vector<uint32_t> todo;
    for (uint32_t i : ids)
      if (!known_[i]) todo.push_back(i);
    auto stopped = [&] { return stop && stop->load(); };
    // The stop flag is polled before every ray: on a large scene one oracle
    // call can still test many triangles (exactly where double precision
    // cannot decide).
    tbb::parallel_for(tbb::blocked_range<size_t>(0, todo.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) {
        if (stopped()) return;
        truth_[todo[k]] = oracle_.closest_hit(rays_[todo[k]]);
      }
    });
    if (stopped()) return;
    for (uint32_t i : todo) known_[i] = 1;
  }
  const OracleHit& operator[](uint32_t i) const { return truth_[i]; }

 private:
  SceneOracle oracle_;
  const std::vector<Ray>& rays_;
  std::vector<OracleHit> truth_;
  std::vector<uint8_t> known_;
};

RaySet subset(const std::vector<Ray>& rays, size_t stride, std::vector<uint32_t>& ids) {
  RaySet s{"stress", false, {}};
  ids.clear();
  for (size_t i = 0; i < rays.size(); i += stride) {
    s.rays.push_back(rays[i]);
    ids.push_back(static_cast<uint32_t>(i));
  }
  return s;
}

// One traced run, timed (also the warm-up of the timing runs).
double timed_trace(const Accelerator& a, const RaySet& set, int threads, TraceOutput& out,
                   const std::atomic<bool>* stop) {
  Timer t;
  trace_set(a, set, threads, out, nullptr, nullptr, stop);
  return t.seconds();
}

// True when the registry accepts the spec (construction only, no build).
bool spec_is_valid(const std::string& text) {
  try {
    make_accelerator(text);
    return true;
  } catch (const SpecError&) {
    return false;
  }
}

}  // namespace

std::vector<std::string> stress_specs_for(const StressScenario& sc, const std::vector<std::string>& specs,
                                          const StressOptions& opt) {
  std::vector<std::string> out;
  auto add = [&](const std::string& s) {
    if (std::find(out.begin(), out.end(), s) == out.end()) out.push_back(s);
  };
  for (const auto& text : specs) {
    add(text);
    if (!sc.watertight() || !opt.add_variants) continue;
    const Spec spec = Spec::parse(text);
    const Capabilities& caps = accelerator_info(spec.name).caps;
    // The robust mode where there is one, else the Moller-Trumbore variant
    // (unless the spec already chose a triangle test).
    const std::string& variant = !caps.robust_variant.empty() ? caps.robust_variant
                                 : spec.params.count("tri")     ? std::string()
                                                                : caps.mt_variant;
    if (variant.empty()) continue;
    const Spec variant_spec = Spec::parse(spec.name + ":" + variant);
    Spec v = spec;
    for (const auto& [key, value] : variant_spec.params) {
      // A variant parameter the spec already set stays as the spec set it.
      if (key == "tri" || !v.params.count(key)) v.params.insert_or_assign(key, value);
    }
    // A variant the spec's other parameters rule out (bvh's is tri=mt on
    // the bvh2 layout, which packet=16 excludes) is replaced by its
    // triangle test alone on the spec's own structure, or dropped.
    if (!spec_is_valid(v.to_string())) {
      if (!variant_spec.params.count("tri")) continue;
      v = spec;
      v.params.insert_or_assign("tri", variant_spec.params.at("tri"));
      if (!spec_is_valid(v.to_string())) continue;
    }
    add(v.to_string());
  }
  return out;
}

namespace {

// One accelerator on one scenario, up to the traced answers and the timing.
struct StressRun {
  std::vector<uint32_t> ids;  // positions in the scenario's rays of the traced subset
  TraceOutput out, occ;       // closest hits, and the any-hit answers on the same rays
};

// Builds the accelerator into the record; false (record complete) on a build error.
bool build_for_stress(const std::string& spec_text, const TriangleMesh& mesh, StressRecord& rec,
                      std::unique_ptr<Accelerator>& accel) {
  const Spec spec = Spec::parse(spec_text);
  const bool reference = accelerator_info(spec.name).caps.reference;
  const bool is_mt = spec.params.count("tri") && spec.params.at("tri") == "mt";
  rec.watertight_test = !reference && !is_mt;
  rec.counts = !reference && !is_mt;
  try {
    accel = make_accelerator(spec_text);
    const BuildStats bs = accel->build(mesh);
    rec.accel = accel->spec();
    rec.build_ms = bs.build_ms;
    rec.bytes = bs.bytes;
    return true;
  } catch (const std::exception& e) {
    rec.status = "build_error";
    rec.error = e.what();
    return false;
  }
}

// The reference's speed: timed back to back with each structure on the same
// rays while it is in memory; after it was released to make room, its time
// on every ray of the scenario (full_s), scaled to the traced subset.
struct ReferenceTiming {
  const Accelerator* accel = nullptr;
  double full_s = 0;
  size_t full_rays = 0;
};

// Probes the speed on a strided sample, then traces the whole set or, if
// that would exceed the time budget, a strided subset; times the
// accelerator and the reference back to back on the same rays.
StressRun trace_for_stress(const Accelerator& accel, const ReferenceTiming& reference, const std::vector<Ray>& rays,
                           const StressOptions& opt, int threads, StressRecord& rec) {
  const size_t n = rays.size();
  size_t stride = 1;
  {
    std::vector<uint32_t> probe_ids;
    const size_t probe_stride = std::max<size_t>(1, n / 1024);
    const RaySet probe = subset(rays, probe_stride, probe_ids);
    TraceOutput po;
    const double projected = timed_trace(accel, probe, threads, po, opt.stop) * static_cast<double>(probe_stride);
    if (projected > opt.time_budget_s) {
      stride = static_cast<size_t>(std::ceil(projected / opt.time_budget_s));
      rec.subsampled = true;
    }
  }
  StressRun run;
  const RaySet set = subset(rays, stride, run.ids);
  rec.rays = set.rays.size();
  // The traced answers, then the timing: the median of 3 runs when they
  // are short (under 0.2 s projected), one run otherwise.
  const double first_s = timed_trace(accel, set, threads, run.out, opt.stop);
  const int repeats = first_s < 0.2 ? 3 : 1;
  const double acc_s = time_trace(accel, set, threads, repeats, nullptr, 0.0, opt.stop).median_s;
  const double emb_s = reference.accel ? time_trace(*reference.accel, set, threads, repeats, nullptr, 0.0, opt.stop).median_s
                                       : reference.full_s * static_cast<double>(set.rays.size()) /
                                             static_cast<double>(std::max<size_t>(1, reference.full_rays));
  rec.reference_timed_first = reference.accel == nullptr;
  RaySet occ_set = set;
  occ_set.occlusion = true;
  trace_set(accel, occ_set, threads, run.occ, nullptr, nullptr, opt.stop);
  rec.mrays_per_s = acc_s > 0 ? rec.rays / acc_s * 1e-6 : 0.0;
  rec.embree_robust_mrays_per_s = emb_s > 0 ? rec.rays / emb_s * 1e-6 : 0.0;
  rec.ratio_to_embree_robust = rec.embree_robust_mrays_per_s > 0 ? rec.mrays_per_s / rec.embree_robust_mrays_per_s : 0.0;
  return run;
}

void dump_wrong(const std::string& scenario, const StressRecord& rec, uint32_t i, const Ray& r, const Hit& a,
                const Hit& e, const OracleHit& t) {
  std::fprintf(stderr, "wrong %s %s ray %u: org %a %a %a dir %a %a %a t [%a, %a]; got prim %u t %g; embree prim %u t %g; oracle %s prim %u t %.17g%s%s\n",
               scenario.c_str(), rec.accel.c_str(), i, r.org.x(), r.org.y(), r.org.z(), r.dir.x(), r.dir.y(), r.dir.z(),
               r.tmin, r.tmax, a.prim, a.t, e.prim, e.t, t.valid ? "hit" : "miss", t.prim, t.t,
               t.grazing ? " grazing" : "", t.exact_used ? " exact" : "");
}

// Disagreements with the reference, screened and then judged by the oracle
// (classify.h); also the degenerate triangles that must never be hit.
void count_disagreements(const StressScenario& sc, const std::string& name, const StressRun& run,
                         const TraceOutput& ref_out, TruthCache& truth, tbb::task_arena& arena, StressRecord& rec,
                         const std::atomic<bool>* stop) {
  std::vector<uint32_t> disagree;  // positions in the traced subset
  DisagreementCounts counts;
  for (size_t k = 0; k < run.ids.size(); ++k) {
    const Hit& a = run.out.hits[k];
    const Hit& e = ref_out.hits[run.ids[k]];
    if (static_cast<bool>(run.occ.occluded[k]) != a.valid()) rec.occlusion_disagree++;
    if (a.valid() && e.valid())
      rec.max_rel_t_err = std::max(rec.max_rel_t_err, std::fabs(static_cast<double>(a.t) - e.t) /
                                                          std::max(1e-30, std::fabs(static_cast<double>(e.t))));
    if (a.valid() && !sc.must_not_hit.empty() && a.prim < sc.must_not_hit.size() && sc.must_not_hit[a.prim]) {
      rec.raylab_wrong++;  // a degenerate triangle was hit
      continue;
    }
    const Screen screen = screen_closest(a, e);
    if (screen == Screen::Tie) counts.ties++;
    if (screen == Screen::Disagree) disagree.push_back(static_cast<uint32_t>(k));
  }
  {
    std::vector<uint32_t> need;
    for (uint32_t k : disagree) need.push_back(run.ids[k]);
    arena.execute([&] { truth.ensure(need, stop); });
  }
  if (stop && stop->load()) return;  // the oracle's answers are incomplete: the record is dropped
  const bool dump = std::getenv("RAYLAB_STRESS_DUMP") != nullptr;
  for (uint32_t k : disagree) {
    const uint32_t i = run.ids[k];
    const Hit& a = run.out.hits[k];
    const Hit& e = ref_out.hits[i];
    const Disagreement d = classify_disagreement(sc.scene.mesh, sc.rays[i], a, e, truth[i]);
    if (d.raylab_wrong && dump) dump_wrong(name, rec, i, sc.rays[i], a, e, truth[i]);
    counts.add(d);
  }
  rec.ties += counts.ties;
  rec.hit_miss_disagree += counts.hit_miss;
  rec.prim_disagree += counts.prim;
  rec.raylab_wrong += counts.raylab_wrong;
  rec.embree_wrong += counts.embree_wrong;
}

// Watertight scenarios: rays from strictly inside that escape, and rays that
// exactly cross the surface from outside but miss it or reach its far side.
void count_leaks(const StressScenario& sc, const StressRun& run, TruthCache& truth, StressRecord& rec) {
  for (size_t k = 0; k < run.ids.size(); ++k) {
    const uint32_t i = run.ids[k];
    const Hit& a = run.out.hits[k];
    if (sc.leak_kind[i] == LeakKind::Inside) {
      rec.leak_rays++;
      if (!a.valid()) rec.leaks++;
    } else if (sc.leak_kind[i] == LeakKind::Outside) {
      const OracleHit& t = truth[i];
      if (!t.valid) continue;  // does not exactly cross the surface: not a leak test ray
      rec.leak_rays++;
      if (!a.valid() || (a.t > t.t && !same_distance(a.t, t.t))) rec.leaks++;
    }
  }
}

const char* stress_status(const StressRecord& rec, const StressOptions& opt) {
  const bool wrong = rec.raylab_wrong > 0 || rec.occlusion_disagree > 0 || (rec.watertight_test && rec.leaks > 0);
  if (wrong) return "wrong";
  if (rec.leaks > 0) return "leaky";
  if (rec.subsampled || rec.ratio_to_embree_robust < opt.slow_ratio) return "slow";
  return "ok";
}

}  // namespace

std::vector<StressRecord> run_stress(const std::vector<std::string>& accel_specs, const StressOptions& opt,
                                     const std::function<void(const StressRecord&)>& progress) {
  const int threads = opt.threads > 0 ? opt.threads : hardware_threads();
  const std::vector<std::string> names = opt.scenarios.empty() ? stress_scenario_names() : opt.scenarios;
  std::vector<StressRecord> records;
  tbb::task_arena arena(threads);
  auto emit = [&](const StressRecord& rec) {
    records.push_back(rec);
    if (progress) progress(rec);
  };

  auto stopped = [&] { return opt.stop && opt.stop->load(); };
  for (size_t scenario_index = 0; scenario_index < names.size() && !stopped(); ++scenario_index) {
    const std::string& name = names[scenario_index];
    if (opt.on_start) opt.on_start(name, "generating", scenario_index, names.size());
    const StressScenario sc = make_stress_scenario(name, opt.ray_scale, opt.seed, opt.scene);
    TruthCache truth(sc.scene.mesh, sc.rays);
    MemoryGuard guard(opt.memory_headroom);
    MemoryStep reference_step = structure_step(opt.reference, sc.scene.mesh, sc.rays.size());
    reference_step.what = "the reference " + opt.reference;
    guard.require(reference_step);
    const size_t before_reference = resident_bytes();
    std::unique_ptr<Accelerator> reference = make_accelerator(opt.reference);
    reference->build(sc.scene.mesh);
    const size_t reference_bytes = resident_bytes() > before_reference ? resident_bytes() - before_reference : 0;
    TraceOutput ref_out;
    const RaySet all{"stress", false, sc.rays};
    trace_set(*reference, all, threads, ref_out, nullptr, nullptr, opt.stop);
    ReferenceTiming ref_timing{reference.get(), 0.0, sc.rays.size()};

    // Leak test: the exact answer for every ray aimed from outside.
    if (sc.watertight()) {
      std::vector<uint32_t> outside;
      for (size_t i = 0; i < sc.rays.size(); ++i)
        if (sc.leak_kind[i] == LeakKind::Outside) outside.push_back(static_cast<uint32_t>(i));
      arena.execute([&] { truth.ensure(outside, opt.stop); });
    }

    for (const auto& spec_text : stress_specs_for(sc, accel_specs, opt)) {
      if (stopped()) break;
      if (opt.on_start) opt.on_start(name, spec_text, scenario_index, names.size());
      StressRecord rec;
      rec.scenario = name;
      rec.accel = spec_text;
      rec.triangles = sc.scene.num_triangles();
      if (!guard.fits(structure_step(spec_text, sc.scene.mesh, sc.rays.size()))) {
        if (reference && guard.fits(structure_step(spec_text, sc.scene.mesh, sc.rays.size()), reference_bytes)) {
          // Fits once the reference's memory is returned: its timing on every
          // ray now (its answers are kept), then released.
          ref_timing.full_s = time_trace(*reference, all, threads, 3).median_s;
          ref_timing.accel = nullptr;
          reference.reset();
        } else {
          if (opt.on_skip)
            opt.on_skip(StructureSkip{name, spec_text, guard.shortage(), rec.triangles, guard.last_estimate(),
                                      guard.last_available()});
          continue;
        }
      }
      std::unique_ptr<Accelerator> accel;
      if (!build_for_stress(spec_text, sc.scene.mesh, rec, accel)) {
        emit(rec);
        continue;
      }
      const StressRun run = trace_for_stress(*accel, ref_timing, sc.rays, opt, threads, rec);
      count_disagreements(sc, name, run, ref_out, truth, arena, rec, opt.stop);
      if (stopped()) break;  // interrupted inside the record: its counts are partial, it is not kept
      if (sc.watertight()) count_leaks(sc, run, truth, rec);
      rec.status = stress_status(rec, opt);
      emit(rec);
    }
  }
  return records;
}

}  // namespace raylab
