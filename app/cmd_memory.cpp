// `raylab memory`: a run's memory plan without running it (checks/memory_guard.h): the
// scene, the stored rays, each step's estimate and the run's peak, as the guard of verify,
// stress, bench, render, show and info will check them. The workflow asks it for each job's
// memory request (`--mb`).
#include <cmath>
#include <cstdio>
#include <memory>

#include <fmt/format.h>

#include "accel/registry.h"
#include "app/commands.h"
#include "checks/memory_guard.h"
#include "checks/process_memory.h"
#include "scenes/scene_registry.h"

namespace raylab::cli {

Runner add_memory(CLI::App& app) {
  struct Opts {
    std::string scene, positional_scene, accel = "bvh", command = "verify", ray_sets = "primary,random", reference;
    size_t rays = 65536, triangles = 0;
    bool mb = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "memory", "a run's memory plan without running it: the scene, the rays and each step's estimated peak");
  add_scene_options(cmd, o->positional_scene, o->scene, "the scene: procedural spec, mesh file or JSON scene file");
  cmd->add_option("--accel", o->accel, "accelerator specs, comma separated, or 'all'")->capture_default_str();
  cmd->add_option("--command", o->command, "the run: verify, stress, bench, render, show or info")
      ->capture_default_str()
      ->check(CLI::IsMember({"verify", "stress", "bench", "render", "show", "info"}));
  add_ray_count_option(cmd, o->rays, "rays per ray set (the largest set)");
  cmd->add_option("--ray-sets", o->ray_sets, "ray sets, comma separated (their number counts)")->capture_default_str();
  cmd->add_option("--reference", o->reference, "the reference (default: embree:robust=1; embree for bench)");
  cmd->add_option("--triangles", o->triangles,
                  "plan for a scene of this many triangles without loading one (registry figures, a vertex soup's size)");
  cmd->add_flag("--mb", o->mb, "print only the peak in MiB, rounded up (a scheduler's memory request)");

  return [o]() {
    const auto specs = expand_accelerator_list(o->accel);
    const size_t sets = parse_name_list(o->ray_sets).size();
    const std::string scene_arg = !o->scene.empty() ? o->scene : o->positional_scene;
    if (scene_arg.empty() == (o->triangles == 0))
      throw std::invalid_argument("give a scene or --triangles N (not both)");
    std::unique_ptr<Scene> scene;
    MemoryPlan plan;
    std::string what;
    if (o->triangles > 0) {
      plan = plan_memory(o->command, specs, o->triangles, o->triangles * kSceneBytesPerTriangle, o->rays, sets,
                         nullptr, o->reference);
      what = fmt::format("{} triangles", group_digits(o->triangles));
    } else {
      scene = std::make_unique<Scene>(load_scene(scene_arg));
      const TriangleMesh& m = scene->mesh;
      const size_t bytes = m.vertices.capacity() * sizeof(Vec3f) + m.triangles.capacity() * sizeof(m.triangles[0]) +
                           scene->material_ids.capacity() * sizeof(uint32_t);
      plan = plan_memory(o->command, specs, m.num_triangles(), bytes, o->rays, sets, &m, o->reference);
      what = fmt::format("{} ({} triangles)", scene->name, group_digits(m.num_triangles()));
    }
    constexpr double kMiB = 1024.0 * 1024.0;
    if (o->mb) {
      std::printf("%.0f\n", std::ceil(static_cast<double>(plan.peak_bytes()) / kMiB));
      return 0;
    }
    MemoryGuard guard;
    std::printf("memory plan of %s on %s\n", o->command.c_str(), what.c_str());
    std::printf("  %-40s %10s\n", "the scene", format_bytes(static_cast<double>(plan.scene_bytes)).c_str());
    if (plan.rays.bytes)
      std::printf("  %-40s %10s\n", plan.rays.what.c_str(), format_bytes(static_cast<double>(plan.rays.bytes)).c_str());
    for (const MemoryStep& s : plan.steps) {
      const bool fits = guard.fits(s);
      std::printf("  %-40s %10s  %s\n", s.what.c_str(), format_bytes(static_cast<double>(s.bytes)).c_str(),
                  fits ? fmt::format("({:.0f} bytes per triangle by {})", s.bytes_per_unit, s.basis).c_str()
                       : ("does not fit now: " + guard.shortage()).c_str());
    }
    const MemoryRoom room = memory_room();
    std::printf("peak: %s (the process, the scene, the rays and the largest step); %s available now (%s), %s resident\n",
                format_bytes(static_cast<double>(plan.peak_bytes())).c_str(),
                format_bytes(static_cast<double>(room.bytes)).c_str(), room.source.c_str(),
                format_bytes(static_cast<double>(resident_bytes())).c_str());
    return 0;
  };
}

}  // namespace raylab::cli
