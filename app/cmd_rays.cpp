// `raylab rays`: write a ray set (and optionally the reference's answers) to
// a ray file (bench/ray_file.h, docs/ray-file.md), so another system can be
// fed exactly the rays `raylab bench` traces.
#include <cstdio>
#include <memory>

#include <fmt/format.h>

#include "accel/registry.h"
#include "app/commands.h"
#include "bench/ray_file.h"
#include "bench/ray_sets.h"
#include "bench/trace.h"
#include "scenes/scene_registry.h"

namespace raylab::cli {

Runner add_rays(CLI::App& app) {
  struct Opts {
    std::string scene, set, size = "512x512", out;
    size_t count = 262144;
    uint64_t seed = 1;
    bool hits = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand("rays", "write a ray set (as raylab bench makes it) to a ray file");
  cmd->add_option("--scene", o->scene, "scene spec, scene file or mesh file")->required();
  cmd->add_option("--set", o->set, "primary, diffuse, shadow or random")->required();
  cmd->add_option("--size", o->size, "primary rays (and the diffuse/shadow rays from their hits): image size WIDTHxHEIGHT")
      ->capture_default_str();
  cmd->add_option("--count", o->count, "random rays: how many")->capture_default_str()->check(CLI::Range(size_t{1}, size_t{1} << 28));
  cmd->add_option("--seed", o->seed, "random seed")->capture_default_str();
  cmd->add_flag("--hits", o->hits, "append the reference's answers (single-ray Embree): hits, or occlusion for shadow rays");
  cmd->add_option("--out", o->out, "ray file to write (docs/ray-file.md)")->required();

  return [o]() {
    bool known = false;
    for (const auto& k : ray_set_names()) known |= k == o->set;
    if (!known) throw std::invalid_argument(fmt::format("unknown ray set '{}' (available: primary, diffuse, shadow, random)", o->set));
    RaySetOptions rso;
    std::tie(rso.width, rso.height) = parse_size(o->size);
    rso.random_count = o->count;
    rso.seed = o->seed;
    const Scene scene = load_scene(o->scene);
    // The same reference and the same generator as `raylab bench`.
    auto reference = make_accelerator("embree");
    reference->build(scene.mesh);
    const RaySet set = make_ray_sets(scene, {o->set}, *reference, rso).front();
    TraceOutput answers;
    if (o->hits) trace_set(*reference, set, 1, answers);
    write_ray_file(o->out, set, o->hits && !set.occlusion ? &answers.hits : nullptr,
                   o->hits && set.occlusion ? &answers.occluded : nullptr);
    std::printf("rays: %zu %s rays of %s%s -> %s\n", set.rays.size(), set.name.c_str(), scene.name.c_str(),
                o->hits ? " with embree's answers" : "", o->out.c_str());
    return 0;
  };
}

}  // namespace raylab::cli
