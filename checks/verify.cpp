#include "checks/verify.h"

#include <algorithm>
#include <cmath>
#include <new>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include "accel/registry.h"
#include "base/spec.h"
#include "checks/classify.h"
#include "checks/oracle.h"
#include "checks/scene_oracle.h"
#include "tracer/trace.h"

namespace raylab {

namespace {

struct Counts {
  DisagreementCounts d;
  size_t occlusion = 0;
  double max_rel = 0.0;
  std::vector<JudgedRay> judged;  // the disagreements the oracle judged, up to `keep` of the lowest ray indices
  size_t keep = 0;

  void note(JudgedRay j) {
    if (keep == 0) return;
    judged.push_back(std::move(j));
    trim();
  }
  void trim() {
    if (judged.size() <= keep) return;
    std::sort(judged.begin(), judged.end(), [](const JudgedRay& a, const JudgedRay& b) { return a.ray < b.ray; });
    judged.resize(keep);
  }
  Counts& operator+=(const Counts& o) {
    d += o.d;
    occlusion += o.occlusion;
    max_rel = std::max(max_rel, o.max_rel);
    judged.insert(judged.end(), o.judged.begin(), o.judged.end());
    trim();
    return *this;
  }
};

const char* verdict_of(const Disagreement& d) {
  return d.raylab_wrong && d.embree_wrong ? "both wrong" : d.raylab_wrong ? "raylab wrong" : d.embree_wrong ? "embree wrong" : "tie";
}

JudgedRay judged_ray(size_t i, const Hit& got, const Hit& ref, const OracleHit& o, const Disagreement& d) {
  return JudgedRay{i, got, ref, o.valid, o.prim, o.t, verdict_of(d)};
}

// Compares closest hits (and the accelerator's own any-hit answers). Ties
// screened by distance go to the oracle too when `judge_ties` is set.
// `stop` is polled per block: the oracle can take long on many disagreements.
Counts compare_closest(const Scene& scene, const SceneOracle& oracle, const RaySet& set, const std::vector<Hit>& ref,
                       const std::vector<Hit>& got, const std::vector<uint8_t>& got_occ, double tol, bool judge_ties,
                       size_t keep, const std::atomic<bool>* stop) {
  Counts init;
  init.keep = keep;
  return tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, set.rays.size(), 512), init,
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
          if (screen == Screen::Tie && !judge_ties) {
            c.d.ties++;
            continue;
          }
          const OracleHit o = oracle.closest_hit(set.rays[i]);
          const Disagreement d = classify_disagreement(scene.mesh, set.rays[i], a, e, o, tol);
          c.d.add(d);
          c.note(judged_ray(i, a, e, o, d));
        }
        return c;
      },
      [](Counts a, const Counts& b) { return a += b; });
}

// Compares occlusion answers.
Counts compare_occlusion(const SceneOracle& oracle, const RaySet& set, const std::vector<uint8_t>& ref,
                         const std::vector<uint8_t>& got, size_t keep, const std::atomic<bool>* stop) {
  Counts init;
  init.keep = keep;
  return tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, set.rays.size(), 512), init,
      [&](const tbb::blocked_range<size_t>& r, Counts c) {
        if (stop && stop->load()) return c;
        for (size_t i = r.begin(); i < r.end(); ++i) {
          if (ref[i] == got[i]) continue;
          const OracleHit o = oracle.closest_hit(set.rays[i]);
          const Disagreement d = classify_occlusion_disagreement(set.rays[i], got[i] != 0, ref[i] != 0, o);
          c.d.add(d);
          Hit g, e;  // occlusion answers: a hit at t = 0 stands for "occluded"
          if (got[i]) g.prim = 0, g.t = 0;
          if (ref[i]) e.prim = 0, e.t = 0;
          c.note(judged_ray(i, g, e, o, d));
        }
        return c;
      },
      [](Counts a, const Counts& b) { return a += b; });
}

// The reference's step: its build beside the stored rays.
MemoryStep reference_step(const std::string& reference, const TriangleMesh& mesh, const MemoryStep& rays) {
  MemoryStep step = structure_step(reference, mesh);
  step.what = "the reference " + reference + " (with the ray sets)";
  step.fixed_bytes += rays.bytes;
  step.bytes += rays.bytes;
  return step;
}

// Checks the reference's step; when it does not fit, the compact robust
// mode (indexed triangles) is named as what would fit instead, if smaller.
void require_reference(MemoryGuard& guard, const std::string& reference, const TriangleMesh& mesh,
                       const MemoryStep& rays) {
  MemoryStep step = reference_step(reference, mesh, rays);
  if (guard.fits(step)) return;
  Spec compact = Spec::parse(reference);
  if (!compact.params.count("compact")) {
    compact.params["compact"] = std::string("1");
    const MemoryStep smaller = reference_step(compact.to_string(), mesh, rays);
    if (smaller.bytes < step.bytes)
      step.instead = fmt::format("--reference {} (~{})", compact.to_string(), format_bytes(static_cast<double>(smaller.bytes)));
  }
  guard.require(step);
}

}  // namespace

std::string format_judged_rays(const std::vector<JudgedRay>& judged) {
  auto answer = [](const Hit& h) { return h.valid() ? fmt::format("prim {} t {:.9g}", h.prim, h.t) : std::string("miss"); };
  std::string s;
  for (const JudgedRay& j : judged)
    s += fmt::format("  ray {}: structure {}; reference {}; oracle {} -> {}\n", j.ray, answer(j.got), answer(j.ref),
                     j.oracle_hit ? fmt::format("prim {} t {:.17g}", j.oracle_prim, j.oracle_t) : std::string("miss"),
                     j.verdict);
  return s;
}

std::vector<VerifyRecord> verify_accelerators(const Scene& scene, const std::vector<std::string>& accel_specs,
                                              const VerifyOptions& opt) {
  const int threads = opt.threads > 0 ? opt.threads : hardware_threads();
  const size_t triangles = scene.num_triangles();
  MemoryGuard guard(opt.memory_headroom);
  // The shared steps first: without the rays and the reference's answers
  // nothing can be checked, so a shortage there stops the run (MemoryShortage).
  const MemoryStep rays_step = ray_sets_step(opt.rays, opt.ray_sets.size());
  guard.require(rays_step);
  require_reference(guard, opt.reference, scene.mesh, rays_step);

  std::vector<RaySet> sets;
  std::vector<TraceOutput> ref_out;
  {
    auto reference = make_accelerator(opt.reference);
    if (opt.on_start) opt.on_start(0, accel_specs.size() * opt.ray_sets.size(), "building the reference " + opt.reference);
    reference->build(scene.mesh);
    RaySetOptions rso;
    rso.jittered_primary = true;
    rso.primary_count = opt.rays;
    rso.random_count = opt.rays;
    rso.seed = opt.seed;
    sets = make_ray_sets(scene, opt.ray_sets, *reference, rso);
    ref_out.resize(sets.size());
    for (size_t s = 0; s < sets.size(); ++s) trace_set(*reference, sets[s], threads, ref_out[s], nullptr, nullptr, opt.stop);
    // Released here: its answers are all the checks need, and its memory is
    // the room of the structures built next.
  }
  size_t largest_set = 0;
  for (const RaySet& set : sets) largest_set = std::max(largest_set, set.rays.size());

  std::vector<VerifyRecord> records;
  auto stopped = [&] { return opt.stop && opt.stop->load(); };
  const size_t total = accel_specs.size() * sets.size();
  const SceneOracle oracle(scene.mesh);  // its index, if any, is built for the first disagreement
  for (const auto& spec : accel_specs) {
    if (stopped()) break;
    auto skip = [&](const std::string& reason) {
      if (opt.on_skip)
        opt.on_skip(StructureSkip{scene.name, spec, reason, triangles, guard.last_estimate(), guard.last_available()});
    };
    if (!guard.fits(structure_step(spec, scene.mesh, largest_set))) {
      skip(guard.shortage());
      continue;
    }
    if (opt.on_start) opt.on_start(records.size(), total, fmt::format("building {}", spec));
    std::unique_ptr<Accelerator> accel;
    BuildStats bs;
    try {
      accel = make_accelerator(spec);
      bs = accel->build(scene.mesh);
    } catch (const std::bad_alloc&) {
      accel.reset();
      skip(fmt::format("out of memory while building (its estimate was ~{})", format_bytes(static_cast<double>(guard.last_estimate()))));
      continue;
    } catch (const SpecError&) {
      throw;  // a bad spec is the caller's error, not this scene's
    } catch (const std::exception& e) {
      // A structure that cannot be built on this scene (a grid whose memory
      // budget cannot hold its references): the others still run.
      accel.reset();
      skip(fmt::format("build failed: {}", e.what()));
      continue;
    }
    for (size_t s = 0; s < sets.size() && !stopped(); ++s) {
      RaySet& set = sets[s];
      if (opt.on_start)
        opt.on_start(records.size(), total, fmt::format("{} on {} {} rays", accel->spec(), set.rays.size(), set.name));
      VerifyRecord rec;
      rec.scene = scene.name;
      rec.accel = accel->spec();
      rec.ray_set = set.name;
      rec.rays = set.rays.size();
      rec.build_ms = bs.build_ms;
      Counts c;
      tbb::task_arena arena(threads);
      if (set.occlusion) {
        TraceOutput out;
        trace_set(*accel, set, threads, out, nullptr, nullptr, opt.stop);
        arena.execute([&] { c = compare_occlusion(oracle, set, ref_out[s].occluded, out.occluded, opt.judged_kept, opt.stop); });
      } else {
        // The closest hits, then the same rays as an occlusion query (the
        // set's flag flipped for it rather than a copy of its rays).
        TraceOutput out, occ;
        trace_set(*accel, set, threads, out, nullptr, nullptr, opt.stop);
        set.occlusion = true;
        trace_set(*accel, set, threads, occ, nullptr, nullptr, opt.stop);
        set.occlusion = false;
        arena.execute([&] {
          c = compare_closest(scene, oracle, set, ref_out[s].hits, out.hits, occ.occluded, kTieTolerance, opt.judge_ties,
                              opt.judged_kept, opt.stop);
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
      std::sort(c.judged.begin(), c.judged.end(), [](const JudgedRay& a, const JudgedRay& b) { return a.ray < b.ray; });
      rec.judged = std::move(c.judged);
      records.push_back(rec);
      if (opt.on_record) opt.on_record(records.back());
    }
  }
  return records;
}

}  // namespace raylab
