// `raylab stress`: every stress scenario against every accelerator (checks/stress.h).
#include <cstdio>
#include <memory>

#include <fmt/format.h>

#include "accel/registry.h"
#include "app/check_json.h"
#include "app/commands.h"
#include "app/progress.h"
#include "bench/report.h"
#include "checks/stress.h"

namespace raylab::cli {

nlohmann::json stress_record_json(const StressRecord& r) {
  // The keys of `raylab verify` first, then the stress-specific ones.
  nlohmann::json j = check_counts_json(r);
  j["scene"] = r.scenario;
  j["ray_set"] = "stress";
  j.update({{"scenario", r.scenario},
            {"status", r.status},
            {"error", r.error},
            {"triangles", r.triangles},
            {"subsampled", r.subsampled},
            {"bytes", r.bytes},
            {"mrays_per_s", r.mrays_per_s},
            {"embree_robust_mrays_per_s", r.embree_robust_mrays_per_s},
            {"ratio_to_embree_robust", r.ratio_to_embree_robust},
            {"watertight_test", r.watertight_test},
            {"counts_for_exit", r.counts},
            {"leak_rays", r.leak_rays},
            {"leaks", r.leaks},
            {"leaks_per_million", r.leaks_per_million()},
            {"reference_timed_first", r.reference_timed_first}});
  return j;
}

Runner add_stress(CLI::App& app) {
  struct Opts {
    std::string accel = "all", scenario, positional_scenario, out, scene;
    double ray_scale = 1.0, budget = 2.0;
    uint64_t seed = 1;
    int threads = 0;
    bool list = false, quiet = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "stress", "run named failure scenarios (precision, degenerate scenes, watertightness, ray corner cases) "
                "against every accelerator, Embree (robust) as the reference, the exact oracle as the judge");
  add_accel_list_option(cmd, o->accel);
  // Stress runs named scenarios rather than scenes: they take the positional place a scene has elsewhere.
  cmd->add_option("scenario", o->positional_scenario,
                  "scenario names or prefixes, comma separated, or 'all' (the default; see --list)");
  cmd->add_option("--scenario", o->scenario, "the scenarios, as the positional argument");
  cmd->add_option("--scene", o->scene,
                  "a scene (spec or file) for the scenarios built on one instead of the Cornell box: rays, far_*, tiny, huge");
  cmd->add_option("--ray-scale", o->ray_scale, "multiply every scenario's ray count")
      ->capture_default_str()
      ->check(CLI::Range(1e-4, 100.0));
  cmd->add_option("--budget", o->budget, "seconds of tracing per scenario x accelerator; slower ones trace a subset")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 3600.0));
  cmd->add_option("--seed", o->seed, "random seed")->capture_default_str();
  add_threads_option(cmd, o->threads);
  cmd->add_option("-o,--out", o->out, "the JSON report (written also when interrupted, with complete false)");
  add_renamed_option(cmd, "--json", "-o/--out FILE");
  cmd->add_flag("--list", o->list, "list the scenarios and exit");
  cmd->add_flag("-q,--quiet", o->quiet, "no progress line");

  return [o]() {
    if (o->list) {
      std::fputs(describe_stress_scenarios().c_str(), stdout);
      return 0;
    }
    const auto specs = expand_accelerator_list(o->accel);
    if (!o->out.empty()) check_output_path(o->out);
    StressOptions so;
    if (!o->scenario.empty() && !o->positional_scenario.empty())
      throw std::invalid_argument(fmt::format("stress takes its scenarios either positionally or with --scenario, not "
                                              "both (got '{}' and '{}')",
                                              o->positional_scenario, o->scenario));
    so.scenarios = expand_stress_scenarios(!o->positional_scenario.empty() ? o->positional_scenario
                                           : !o->scenario.empty()         ? o->scenario
                                                                          : std::string("all"));
    so.ray_scale = o->ray_scale;
    so.time_budget_s = o->budget;
    so.seed = o->seed;
    so.threads = o->threads;
    so.scene = o->scene;
    if (!so.scene.empty())
      for (const auto& name : so.scenarios)
        if (!stress_scenario_takes_scene(name))
          throw std::invalid_argument(fmt::format("--scene: scenario '{}' makes its own scene (a scene is taken by rays, "
                                                  "far_1e3, far_1e5, far_1e7, tiny and huge)", name));
    InterruptGuard interrupt;  // from here on Ctrl-C keeps the finished records
    std::printf("stress: %zu scenario%s x %zu accelerator%s, reference %s (emb:rob, timed back to back; its "
                "ratios are to it, not to bench's default embree), judge: exact oracle\n",
                so.scenarios.size(), so.scenarios.size() == 1 ? "" : "s", specs.size(), specs.size() == 1 ? "" : "s",
                so.reference.c_str());
    std::printf("%-18s %-26s %-11s %9s %8s %10s %8s %8s %9s %9s %7s %6s %6s %6s %7s %9s\n", "scenario", "accel", "status",
                "tris", "rays", "build ms", "MiB", "Mrays/s", "emb:rob", "x emb:rob", "disagr", "ties", "rl_wr", "em_wr",
                "leaks", "leaks/M");
    std::fflush(stdout);
    bool failed = false;
    size_t n_failed = 0;
    ProgressLine progress("stress", !o->quiet && stderr_is_terminal());
    CheckReport report("stress", o->out);
    so.stop = interrupt.flag();
    size_t finished = 0;
    so.on_start = [&](const std::string& scenario, const std::string& accel, size_t i, size_t n) {
      progress.update(i, n, fmt::format("scenario {} ({}), {} records done", scenario, accel, finished));
    };
    so.on_skip = [&](const StructureSkip& s) {
      progress.clear();
      report.skip(s);
    };
    auto on_record = [&](const StressRecord& r) {
      ++finished;
      progress.clear();
      std::printf("%-18s %-26s %-11s %9zu %8zu %10.1f %8.2f %8.3g %9.3g %9.3g %7zu %6zu %6zu %6zu %7zu %9.1f%s\n",
                  r.scenario.c_str(), r.accel.c_str(), r.status.c_str(), r.triangles, r.rays, r.build_ms,
                  r.bytes / 1048576.0, r.mrays_per_s, r.embree_robust_mrays_per_s, r.ratio_to_embree_robust,
                  r.hit_miss_disagree + r.prim_disagree, r.ties, r.raylab_wrong, r.embree_wrong, r.leaks,
                  r.leaks_per_million(), r.error.empty() ? "" : fmt::format("  ({})", r.error).c_str());
      std::fflush(stdout);
      if (r.failed()) {
        failed = true;
        n_failed++;
      }
      report.add(stress_record_json(r));
    };
    try {
      run_stress(specs, so, on_record);
    } catch (const MemoryShortage& e) {
      progress.clear();
      return report.stop(e);
    }
    progress.clear();
    if (!interrupt.interrupted())
      std::printf("stress: %zu records, %zu failed (raylab_wrong, occlusion disagreement or watertight leak)\n",
                  report.records().size(), n_failed);
    return report.finish(interrupt.interrupted(), failed);
  };
}

}  // namespace raylab::cli
