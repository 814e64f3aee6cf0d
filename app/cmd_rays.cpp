// `raylab rays`: write a ray set (and optionally the reference's answers) to
// a ray file (bench/ray_file.h, docs/ray-file.md), so another system can be
// fed exactly the rays `raylab bench` traces.
#include <cstdio>
#include <memory>

#include <fmt/format.h>

#include "accel/registry.h"
#include "app/commands.h"
#include "bench/ray_file.h"
#include "tracer/ray_sets.h"
#include "tracer/trace.h"
#include "scenes/scene_registry.h"

namespace raylab::cli {

Runner add_rays(CLI::App& app) {
  struct Opts {
    std::string scene, positional_scene, set, size = "512x512", out;
    size_t count = 262144;
    uint64_t seed = 1;
    bool hits = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand("rays", "write a ray set (as raylab bench makes it) to a ray file");
  // The vocabulary of verify and bench: a positional scene,
  // --ray-sets for which set, --rays for how many, -o for the output; the
  // first names (--set, --count, --out) are kept as synonyms.
  add_scene_options(cmd, o->positional_scene, o->scene, "the scene: procedural spec, scene file or mesh file");
  cmd->add_option("--ray-sets,--set", o->set, "the ray set: primary, diffuse, shadow or random (one)")->required();
  cmd->add_option("--size", o->size, "primary rays (and the diffuse/shadow rays from their hits): image size WIDTHxHEIGHT")
      ->capture_default_str();
  add_ray_count_option(cmd, o->count, "random rays: how many", "--rays,--count");
  cmd->add_option("--seed", o->seed, "random seed")->capture_default_str();
  cmd->add_flag("--hits", o->hits, "append the reference's answers (single-ray Embree): hits, or occlusion for shadow rays");
  cmd->add_option("-o,--out", o->out, "ray file to write (docs/ray-file.md)")->required();

  return [o]() {
    if (o->set.find(',') != std::string::npos)
      throw std::invalid_argument(fmt::format("rays writes one ray set per file, '{}' names several", o->set));
    check_ray_set_names({o->set});
    RaySetOptions rso;
    std::tie(rso.width, rso.height) = parse_size(o->size);
    rso.random_count = o->count;
    rso.seed = o->seed;
    const std::string scene_arg = pick_scene("rays", o->scene, o->positional_scene, "");
    if (scene_arg.empty()) throw std::invalid_argument("rays needs a scene (positional or --scene)");
    const Scene scene = load_scene(scene_arg);
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
