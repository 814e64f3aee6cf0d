#include "checks/verify.h"

#include <cmath>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include "accel/registry.h"
#include "checks/classify.h"
#include "checks/oracle.h"
#include "tracer/trace.h"

namespace raylab {

namespace {

struct Counts {
  DisagreementCounts d;
  size_t occlusion = 0;
  double max_rel = 0.0;
  Counts& operator+=(const Counts& o) {
    d += o.d;
    occlusion += o.occlusion;
    max_rel = std::max(max_rel, o.max_rel);
    return *this;
  }
};

// Compares closest hits (and the accelerator's own any-hit answers).
// `stop` is polled per block: the oracle can take long on many disagreements.
Counts compare_closest(const Scene& scene, const RaySet& set, const std::vector<Hit>& ref, const std::vector<Hit>& got,
                       const std::vector<uint8_t>& got_occ, double tol, const std::atomic<bool>* stop) {
  return tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, set.rays.size(), 512), Counts{},
      [&](const tbb::blocked_range<size_t>& r, Counts c) {
        if (stop && stop->load()) return c;
        for (size_t i = r.begin(); i < r.end(); ++i) {
          const Hit& e = ref[i];
          const Hit& a = got[i];
          if (static_cast<bool>(got_occ[i]) != a.valid()) c.occlusion++;
          if (e.valid() && a.valid())
            c.max_rel = std::max(c.max_rel, std::fabs(static_cast<double>(a.t) - e.t) / std::max(1e-30, std::fabs(static_cast<double>(e.t))));
          const Screen screen = screen_closest(a, e, tol);
          if (screen == Screen::Agree) continue;
          if (screen == Screen::Tie) {
            c.d.ties++;
            continue;
          }
          const OracleHit o = oracle_closest_hit(scene.mesh, set.rays[i]);
          c.d.add(classify_disagreement(scene.mesh, set.rays[i], a, e, o, tol));
        }
        return c;
      },
      [](Counts a, const Counts& b) { return a += b; });
}

// Compares occlusion answers.
Counts compare_occlusion(const Scene& scene, const RaySet& set, const std::vector<uint8_t>& ref,
                         const std::vector<uint8_t>& got, const std::atomic<bool>* stop) {
  return tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, set.rays.size(), 512), Counts{},
      [&](const tbb::blocked_range<size_t>& r, Counts c) {
        if (stop && stop->load()) return c;
        for (size_t i = r.begin(); i < r.end(); ++i) {
          if (ref[i] == got[i]) continue;
          const OracleHit o = oracle_closest_hit(scene.mesh, set.rays[i]);
          c.d.add(classify_occlusion_disagreement(set.rays[i], got[i] != 0, ref[i] != 0, o));
        }
        return c;
      },
      [](Counts a, const Counts& b) { return a += b; });
}

}  // namespace

std::vector<VerifyRecord> verify_accelerators(const Scene& scene, const std::vector<std::string>& accel_specs,
                                              const VerifyOptions& opt) {
  const int threads = opt.threads > 0 ? opt.threads : hardware_threads();
  auto reference = make_accelerator(opt.reference);
  reference->build(scene.mesh);

  RaySetOptions rso;
  rso.jittered_primary = true;
  rso.primary_count = opt.rays;
  rso.random_count = opt.rays;
  rso.seed = opt.seed;
  const std::vector<RaySet> sets = make_ray_sets(scene, opt.ray_sets, *reference, rso);

  std::vector<TraceOutput> ref_out(sets.size());
  for (size_t s = 0; s < sets.size(); ++s) trace_set(*reference, sets[s], threads, ref_out[s], nullptr, nullptr, opt.stop);

  std::vector<VerifyRecord> records;
  auto stopped = [&] { return opt.stop && opt.stop->load(); };
  const size_t total = accel_specs.size() * sets.size();
  for (const auto& spec : accel_specs) {
    if (stopped()) break;
    if (opt.on_start) opt.on_start(records.size(), total, fmt::format("building {}", spec));
    auto accel = make_accelerator(spec);
    const BuildStats bs = accel->build(scene.mesh);
    for (size_t s = 0; s < sets.size() && !stopped(); ++s) {
      const RaySet& set = sets[s];
      if (opt.on_start)
        opt.on_start(records.size(), total, fmt::format("{} on {} {} rays", accel->spec(), set.rays.size(), set.name));
      VerifyRecord rec;
      rec.scene = scene.name;
      rec.accel = accel->spec();
      rec.ray_set = set.name;
      rec.rays = set.rays.size();
      rec.build_ms = bs.build_ms;
      TraceOutput out;
      trace_set(*accel, set, threads, out, nullptr, nullptr, opt.stop);
      Counts c;
      tbb::task_arena arena(threads);
      if (set.occlusion) {
        arena.execute([&] { c = compare_occlusion(scene, set, ref_out[s].occluded, out.occluded, opt.stop); });
      } else {
        RaySet as_occlusion = set;
        as_occlusion.occlusion = true;
        TraceOutput occ;
        trace_set(*accel, as_occlusion, threads, occ, nullptr, nullptr, opt.stop);
        arena.execute([&] {
          c = compare_closest(scene, set, ref_out[s].hits, out.hits, occ.occluded, kTieTolerance, opt.stop);
        });
      }
      if (stopped()) break;  // interrupted inside the record: its counts are partial, it is not kept
      rec.hit_miss_disagree = c.d.hit_miss;
      rec.prim_disagree = c.d.prim;
      rec.ties = c.d.ties;
      rec.raylab_wrong = c.d.raylab_wrong;
      rec.embree_wrong = c.d.embree_wrong;
      rec.occlusion_disagree = c.occlusion;
      rec.max_rel_t_err = c.max_rel;
      records.push_back(rec);
      if (opt.on_record) opt.on_record(rec);
    }
  }
  return records;
}

}  // namespace raylab
