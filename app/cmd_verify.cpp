#include <cstdio>
#include <memory>

#include <fmt/format.h>

#include "accel/registry.h"
#include "app/check_json.h"
#include "app/commands.h"
#include "bench/report.h"
#include "checks/verify.h"
#include "scenes/scene_registry.h"

namespace raylab::cli {

nlohmann::json verify_record_json(const VerifyRecord& r) {
  nlohmann::json j = check_counts_json(r);
  j["scene"] = r.scene;
  j["ray_set"] = r.ray_set;
  return j;
}

Runner add_verify(CLI::App& app) {
  struct Opts {
    std::string scene = "cornell", accel = "bvh,brute", ray_sets = "primary,random", json;
    size_t rays = 65536;
    uint64_t seed = 1;
    int threads = 0;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand("verify", "compare accelerators' hits with Embree (robust) on the same rays");
  cmd->add_option("--scene", o->scene, "procedural scene spec or mesh file")->capture_default_str();
  cmd->add_option("--accel", o->accel, "accelerator specs, comma separated, or 'all'")->capture_default_str();
  cmd->add_option("--rays", o->rays, "rays per ray set")->capture_default_str()->check(CLI::Range(size_t{1}, size_t{1} << 28));
  cmd->add_option("--ray-sets", o->ray_sets, "primary, random, diffuse, shadow")->capture_default_str();
  cmd->add_option("--seed", o->seed, "random seed")->capture_default_str();
  cmd->add_option("--threads", o->threads, "threads (0 = all cores)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--json", o->json, "write records to this JSON file");

  return [o]() {
    const auto specs = expand_accelerator_list(o->accel);
    VerifyOptions vo;
    vo.rays = o->rays;
    vo.seed = o->seed;
    vo.threads = o->threads;
    vo.ray_sets = parse_name_list(o->ray_sets);
    const Scene scene = load_scene(o->scene);
    const auto records = verify_accelerators(scene, specs, vo);
    std::printf("verify %s (%zu triangles) against %s\n", scene.name.c_str(), scene.num_triangles(), vo.reference.c_str());
    std::printf("%-28s %-8s %8s %9s %9s %6s %12s %12s %9s %11s  %s\n", "accel", "rays", "count", "hit/miss", "prim", "ties",
                "raylab_wrong", "embree_wrong", "occl", "max rel t", "result");
    bool failed = false;
    nlohmann::json recs = nlohmann::json::array();
    for (const auto& r : records) {
      std::printf("%-28s %-8s %8zu %9zu %9zu %6zu %12zu %12zu %9zu %11.3g  %s\n", r.accel.c_str(), r.ray_set.c_str(),
                  r.rays, r.hit_miss_disagree, r.prim_disagree, r.ties, r.raylab_wrong, r.embree_wrong,
                  r.occlusion_disagree, r.max_rel_t_err, r.failed() ? "FAIL" : "ok");
      failed |= r.failed();
      recs.push_back(verify_record_json(r));
    }
    if (!o->json.empty()) write_json_report(o->json, report_header("verify"), recs);
    return failed ? kExitCheckFailed : 0;
  };
}

}  // namespace raylab::cli
