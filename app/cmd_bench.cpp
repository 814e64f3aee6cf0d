#include <unistd.h>

#include <cstdio>
#include <memory>

#include <fmt/format.h>

#include "accel/registry.h"
#include "app/commands.h"
#include "bench/bench_run.h"
#include "bench/report.h"
#include "scenes/scene_registry.h"

namespace raylab::cli {

Runner add_bench(CLI::App& app) {
  struct Opts {
    std::string scene = "cornell", accel = "embree,bvh", rays = "primary,random", threads = "1", size = "512x512", json;
    std::vector<std::string> sweeps;
    size_t random_rays = 262144;
    int repeats = 5;
    uint64_t seed = 1;
    bool quiet = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand("bench", "time accelerators on the same rays, as ratios to Embree");
  cmd->add_option("--scene", o->scene, "procedural scene spec or mesh file")->capture_default_str();
  cmd->add_option("--accel", o->accel, "accelerator specs, comma separated, or 'all'")->capture_default_str();
  cmd->add_option("--rays", o->rays, "ray sets: primary, diffuse, shadow, random")->capture_default_str();
  cmd->add_option("--threads", o->threads, "thread counts, comma separated")->capture_default_str();
  cmd->add_option("--size", o->size, "primary rays: image size WIDTHxHEIGHT")->capture_default_str();
  cmd->add_option("--random-rays", o->random_rays, "number of random rays")->capture_default_str()->check(CLI::Range(size_t{1}, size_t{1} << 28));
  cmd->add_option("--repeats", o->repeats, "timed repeats (median reported)")->capture_default_str()->check(CLI::Range(1, 1000));
  cmd->add_option("--seed", o->seed, "random seed")->capture_default_str();
  cmd->add_option("--sweep", o->sweeps, "PARAM=v1,v2,...: one run per value for every accelerator with PARAM (repeatable)");
  cmd->add_option("--json", o->json, "write records to this JSON file");
  cmd->add_flag("--quiet", o->quiet, "no progress line");

  return [o]() {
    auto specs = expand_accelerator_list(o->accel);
    for (const auto& sweep : o->sweeps) {
      const auto eq = sweep.find('=');
      if (eq == std::string::npos || eq == 0)
        throw std::invalid_argument(fmt::format("--sweep {}: expected PARAM=v1,v2,...", sweep));
      specs = apply_sweep(specs, sweep.substr(0, eq), parse_name_list(sweep.substr(eq + 1)));
    }
    BenchOptions bo;
    bo.ray_sets = parse_name_list(o->rays);
    bo.threads = parse_int_list(o->threads, "thread count");
    std::tie(bo.width, bo.height) = parse_size(o->size);
    bo.random_rays = o->random_rays;
    bo.repeats = o->repeats;
    bo.seed = o->seed;
    const Scene scene = load_scene(o->scene);
    const bool tty = !o->quiet && isatty(fileno(stderr));
    BenchProgress progress;
    if (tty)
      progress = [](const std::string& m) {
        std::fprintf(stderr, "\r\033[K%s", m.c_str());
        std::fflush(stderr);
      };
    const auto records = run_bench(scene, specs, bo, progress);
    if (tty) std::fprintf(stderr, "\r\033[K");
    std::printf("bench %s (%zu triangles)\n%s", scene.name.c_str(), scene.num_triangles(),
                format_bench_table(records).c_str());
    if (!o->json.empty()) {
      nlohmann::json recs = nlohmann::json::array();
      for (const auto& r : records) recs.push_back(r.to_json());
      write_json_report(o->json, report_header("bench"), recs);
    }
    return 0;
  };
}

}  // namespace raylab::cli
