#include <algorithm>
#include <cstdio>
#include <memory>
#include <set>

#include <fmt/format.h>

#include "accel/registry.h"
#include "app/check_json.h"
#include "app/commands.h"
#include "app/progress.h"
#include "bench/report.h"
#include "checks/verify.h"
#include "scenes/scene_registry.h"

namespace raylab::cli {

nlohmann::json verify_record_json(const VerifyRecord& r) {
  nlohmann::json j = check_counts_json(r);
  j["scene"] = r.scene;
  j["ray_set"] = r.ray_set;
  j["judged"] = judged_rays_json(r.judged);
  return j;
}

Runner add_verify(CLI::App& app) {
  struct Opts {
    std::string scene, positional_scene, accel = "bvh;brute", ray_sets = "primary,random", out,
        reference = "embree:robust=1";
    size_t rays = 65536;
    uint64_t seed = 1;
    int threads = 0;
    bool quiet = false, judge_ties = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand("verify", "compare accelerators' hits with Embree (robust) on the same rays");
  add_scene_options(cmd, o->positional_scene, o->scene,
                    "the scene: procedural spec, mesh file or JSON scene file (default cornell)");
  add_accel_list_option(cmd, o->accel);
  add_ray_count_option(cmd, o->rays, "rays per ray set");
  cmd->add_option("--ray-sets", o->ray_sets, "ray sets, comma separated: primary, random, diffuse, shadow")->capture_default_str();
  cmd->add_option("--seed", o->seed, "random seed")->capture_default_str();
  add_threads_option(cmd, o->threads);
  cmd->add_option("-o,--out", o->out, "the JSON report (written also when interrupted, with complete false)");
  add_renamed_option(cmd, "--json", "-o/--out FILE");
  cmd->add_flag("-q,--quiet", o->quiet, "no progress line");
  cmd->add_option("--reference", o->reference, "the reference: an Embree spec (e.g. embree:robust=1,compact=1, smaller)")
      ->capture_default_str();
  cmd->add_flag("--judge-ties", o->judge_ties,
                "the oracle judges ties too (different triangles at the same distance within 1e-4; large scenes)");

  return [o]() {
    const auto specs = expand_accelerator_list(o->accel);
    VerifyOptions vo;
    vo.rays = o->rays;
    vo.seed = o->seed;
    vo.threads = o->threads;
    vo.ray_sets = parse_name_list(o->ray_sets);
    vo.reference = o->reference;
    if (!is_reference_spec(vo.reference))
      throw std::invalid_argument(fmt::format("--reference {}: the reference is an Embree spec (embree:...)", vo.reference));
    make_accelerator(vo.reference);  // its parameters checked before the scene loads
    vo.judge_ties = o->judge_ties;
    check_ray_set_names(vo.ray_sets);  // before loading a possibly large scene
    if (!o->out.empty()) check_output_path(o->out);
    const Scene scene = load_scene(pick_scene("verify", o->scene, o->positional_scene, "cornell"));
    InterruptGuard interrupt;  // from here on Ctrl-C keeps the finished records
    std::printf("verify %s (%zu triangle%s) against %s\n", scene.name.c_str(), scene.num_triangles(),
                scene.num_triangles() == 1 ? "" : "s", vo.reference.c_str());
    std::printf("%-28s %-8s %8s %9s %9s %6s %12s %12s %9s %11s  %s\n", "accel", "rays", "count", "hit/miss", "prim", "ties",
                "raylab_wrong", "embree_wrong", "occl", "max rel dt", "result");
    std::fflush(stdout);

    ProgressLine progress("verify", !o->quiet && stderr_is_terminal());
    CheckReport report("verify", o->out);
    bool failed = false;
    std::set<std::string> noted;
    vo.stop = interrupt.flag();
    vo.on_start = [&](size_t i, size_t n, const std::string& what) { progress.update(i, n, what); };
    vo.on_skip = [&](const StructureSkip& s) {
      progress.clear();
      report.skip(s);
    };
    vo.on_record = [&](const VerifyRecord& r) {
      progress.clear();
      std::printf("%-28s %-8s %8zu %9zu %9zu %6zu %12zu %12zu %9zu %11.3g  %s\n", r.accel.c_str(), r.ray_set.c_str(),
                  r.rays, r.hit_miss_disagree, r.prim_disagree, r.ties, r.raylab_wrong, r.embree_wrong,
                  r.occlusion_disagree, r.max_rel_t_err, r.failed() ? "FAIL" : "ok");
      std::fputs(format_judged_rays(r.judged).c_str(), stdout);
      std::fflush(stdout);
      failed |= r.failed();
      report.add(verify_record_json(r));
      if (noted.insert(r.ray_set).second) std::fputs(ray_set_size_note(r.ray_set, o->rays, r.rays).c_str(), stderr);
    };
    try {
      verify_accelerators(scene, specs, vo);
    } catch (const MemoryShortage& e) {
      progress.clear();
      return report.stop(e);
    }
    progress.clear();
    return report.finish(interrupt.interrupted(), failed);
  };
}

}  // namespace raylab::cli
