// The runner of `raylab stress` (bench/stress.h).
#include "bench/stress.h"

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
#include "accel/spec.h"
#include "accel/util/timer.h"
#include "bench/oracle.h"
#include "bench/trace.h"

namespace raylab {

namespace {

bool same_distance(double a, double b, double tol) {
  return std::fabs(a - b) <= tol * std::max({std::fabs(a), std::fabs(b), 1e-30});
}

bool has_param(const std::string& name, const std::string& param) {
  for (const auto& info : accelerator_registry())
    if (info.name == name)
      for (const auto& p : info.params)
        if (p.name == param) return true;
  return false;
}

// The oracle's answers, computed once per ray of a scenario and shared by
// every accelerator (Embree's own mistakes make every accelerator disagree
// on the same rays).
class TruthCache {
 public:
  TruthCache(const TriangleMesh& mesh, const std::vector<Ray>& rays)
      : mesh_(mesh), rays_(rays), truth_(rays.size()), known_(rays.size(), 0) {}

  // Computes the missing answers for `ids` in parallel (call outside parallel loops over the same ids).
  void ensure(const std::vector<uint32_t>& ids) {
    std::vector<uint32_t> todo;
    for (uint32_t i : ids)
      if (!known_[i]) todo.push_back(i);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, todo.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) truth_[todo[k]] = oracle_closest_hit(mesh_, rays_[todo[k]]);
    });
    for (uint32_t i : todo) known_[i] = 1;
  }
  const OracleHit& operator[](uint32_t i) const { return truth_[i]; }

 private:
  const TriangleMesh& mesh_;
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
double timed_trace(const Accelerator& a, const RaySet& set, int threads, TraceOutput& out) {
  Timer t;
  trace_set(a, set, threads, out);
  return t.seconds();
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
    Spec spec = Spec::parse(text);
    if (spec.name == "embree") {
      Spec robust = spec;
      robust.params.insert_or_assign("robust", std::string(1, '1'));
      add(robust.to_string());
    } else if (has_param(spec.name, "tri") && !spec.params.count("tri")) {
      spec.params.insert_or_assign("tri", std::string("mt"));
      // The wide BVH layouts have only the vectorised watertight test.
      if (spec.name == "bvh" && !spec.params.count("layout")) spec.params.insert_or_assign("layout", std::string("bvh2"));
      add(spec.to_string());
    }
  }
  return out;
}

std::vector<StressRecord> run_stress(const std::vector<std::string>& accel_specs, const StressOptions& opt,
                                     const std::function<void(const StressRecord&)>& progress) {
  const int threads = opt.threads > 0 ? opt.threads : hardware_threads();
  const std::vector<std::string> names = opt.scenarios.empty() ? stress_scenario_names() : opt.scenarios;
  std::vector<StressRecord> records;
  tbb::task_arena arena(threads);

  auto stopped = [&] { return opt.stop && opt.stop->load(); };
  for (size_t scenario_index = 0; scenario_index < names.size() && !stopped(); ++scenario_index) {
    const std::string& name = names[scenario_index];
    if (opt.on_start) opt.on_start(name, "generating", scenario_index, names.size());
    const StressScenario sc = make_stress_scenario(name, opt.ray_scale, opt.seed);
    const std::vector<Ray>& rays = sc.rays;
    const size_t n = rays.size();
    TruthCache truth(sc.scene.mesh, rays);

    auto reference = make_accelerator(opt.reference);
    reference->build(sc.scene.mesh);
    RaySet all{"stress", false, rays};
    TraceOutput ref_out;
    trace_set(*reference, all, threads, ref_out);

    // Leak test: the exact answer for every ray aimed from outside.
    if (sc.watertight()) {
      std::vector<uint32_t> outside;
      for (size_t i = 0; i < n; ++i)
        if (sc.leak_kind[i] == LeakKind::Outside) outside.push_back(static_cast<uint32_t>(i));
      arena.execute([&] { truth.ensure(outside); });
    }

    for (const auto& spec_text : stress_specs_for(sc, accel_specs, opt)) {
      if (stopped()) break;
      if (opt.on_start) opt.on_start(name, spec_text, scenario_index, names.size());
      StressRecord rec;
      rec.scenario = name;
      rec.accel = spec_text;
      rec.triangles = sc.scene.num_triangles();
      const Spec spec = Spec::parse(spec_text);
      const bool is_embree = spec.name == "embree";
      const bool is_mt = spec.params.count("tri") && spec.params.at("tri") == "mt";
      rec.watertight_test = !is_embree && !is_mt;
      rec.counts = !is_embree && !is_mt;

      std::unique_ptr<Accelerator> accel;
      try {
        accel = make_accelerator(spec_text);
        const BuildStats bs = accel->build(sc.scene.mesh);
        rec.accel = accel->spec();
        rec.build_ms = bs.build_ms;
        rec.bytes = bs.bytes;
      } catch (const std::exception& e) {
        rec.status = "build_error";
        rec.error = e.what();
        records.push_back(rec);
        if (progress) progress(rec);
        continue;
      }

      // Probe the speed on a strided sample; trace a strided subset if the whole set would exceed the budget.
      size_t stride = 1;
      {
        std::vector<uint32_t> probe_ids;
        const size_t probe_stride = std::max<size_t>(1, n / 1024);
        const RaySet probe = subset(rays, probe_stride, probe_ids);
        TraceOutput po;
        const double s = timed_trace(*accel, probe, threads, po);
        const double projected = s * static_cast<double>(probe_stride);
        if (projected > opt.time_budget_s) {
          stride = static_cast<size_t>(std::ceil(projected / opt.time_budget_s));
          rec.subsampled = true;
        }
      }
      std::vector<uint32_t> ids;
      const RaySet set = subset(rays, stride, ids);
      rec.rays = set.rays.size();
      TraceOutput out, occ;
      // The traced answers, then the timing: the median of 3 runs when they
      // are short (under 0.2 s projected), one run otherwise; Embree robust
      // is timed the same way on the same rays, back to back.
      const double first_s = timed_trace(*accel, set, threads, out);
      const int repeats = first_s < 0.2 ? 3 : 1;
      const double acc_s = time_trace(*accel, set, threads, repeats).median_s;
      const double emb_s = time_trace(*reference, set, threads, repeats).median_s;
      RaySet occ_set = set;
      occ_set.occlusion = true;
      trace_set(*accel, occ_set, threads, occ);
      rec.mrays_per_s = acc_s > 0 ? rec.rays / acc_s * 1e-6 : 0.0;
      rec.embree_mrays_per_s = emb_s > 0 ? rec.rays / emb_s * 1e-6 : 0.0;
      rec.ratio = rec.embree_mrays_per_s > 0 ? rec.mrays_per_s / rec.embree_mrays_per_s : 0.0;

      // Disagreements with the reference, and rays whose exact answer the leak test needs.
      std::vector<uint32_t> disagree;  // positions in `set`
      for (size_t k = 0; k < ids.size(); ++k) {
        const Hit& a = out.hits[k];
        const Hit& e = ref_out.hits[ids[k]];
        if (static_cast<bool>(occ.occluded[k]) != a.valid()) rec.occlusion_disagree++;
        if (a.valid() && e.valid())
          rec.max_rel_t_err = std::max(rec.max_rel_t_err, std::fabs(static_cast<double>(a.t) - e.t) /
                                                              std::max(1e-30, std::fabs(static_cast<double>(e.t))));
        if (a.valid() && !sc.must_not_hit.empty() && a.prim < sc.must_not_hit.size() && sc.must_not_hit[a.prim]) {
          rec.raylab_wrong++;  // a degenerate triangle was hit
          continue;
        }
        if (e.valid() != a.valid() || (a.valid() && a.prim != e.prim)) {
          if (a.valid() && e.valid() && same_distance(a.t, e.t, opt.tie_tolerance)) {
            rec.ties++;
            continue;
          }
          disagree.push_back(static_cast<uint32_t>(k));
        }
      }
      {
        std::vector<uint32_t> need;
        for (uint32_t k : disagree) need.push_back(ids[k]);
        arena.execute([&] { truth.ensure(need); });
      }
      for (uint32_t k : disagree) {
        const uint32_t i = ids[k];
        const Hit& a = out.hits[k];
        const Hit& e = ref_out.hits[i];
        const Verdict va = oracle_judge(sc.scene.mesh, rays[i], a, truth[i], opt.tie_tolerance);
        const Verdict ve = oracle_judge(sc.scene.mesh, rays[i], e, truth[i], opt.tie_tolerance);
        if (va == Verdict::Wrong) rec.raylab_wrong++;
        if (ve == Verdict::Wrong) rec.embree_wrong++;
        if (va == Verdict::Wrong && std::getenv("RAYLAB_STRESS_DUMP"))
          std::fprintf(stderr, "wrong %s %s ray %u: org %a %a %a dir %a %a %a t [%a, %a]; got prim %u t %g; embree prim %u t %g; oracle %s prim %u t %.17g%s%s\n",
                       name.c_str(), rec.accel.c_str(), i, rays[i].org.x(), rays[i].org.y(), rays[i].org.z(), rays[i].dir.x(),
                       rays[i].dir.y(), rays[i].dir.z(), rays[i].tmin, rays[i].tmax, a.prim, a.t, e.prim, e.t,
                       truth[i].valid ? "hit" : "miss", truth[i].prim, truth[i].t, truth[i].grazing ? " grazing" : "",
                       truth[i].exact_used ? " exact" : "");
        if (va != Verdict::Wrong && ve != Verdict::Wrong) rec.ties++;
        else if (a.valid() != e.valid()) rec.hit_miss_disagree++;
        else rec.prim_disagree++;
      }
      if (sc.watertight()) {
        for (size_t k = 0; k < ids.size(); ++k) {
          const uint32_t i = ids[k];
          const Hit& a = out.hits[k];
          if (sc.leak_kind[i] == LeakKind::Inside) {
            rec.leak_rays++;
            if (!a.valid()) rec.leaks++;
          } else if (sc.leak_kind[i] == LeakKind::Outside) {
            const OracleHit& t = truth[i];
            if (!t.valid) continue;  // does not exactly cross the surface: not a leak test ray
            rec.leak_rays++;
            if (!a.valid() || (a.t > t.t && !same_distance(a.t, t.t, opt.tie_tolerance))) rec.leaks++;
          }
        }
      }
      const bool wrong = rec.raylab_wrong > 0 || rec.occlusion_disagree > 0 || (rec.watertight_test && rec.leaks > 0);
      rec.status = wrong                                       ? "wrong"
                   : rec.leaks > 0                             ? "leaky"
                   : (rec.subsampled || rec.ratio < opt.slow_ratio) ? "slow"
                                                               : "ok";
      records.push_back(rec);
      if (progress) progress(rec);
    }
  }
  return records;
}

}  // namespace raylab
