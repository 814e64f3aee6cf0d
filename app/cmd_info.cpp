#include <cstdio>
#include <memory>

#include "accel/registry.h"
#include "accel/util/timer.h"
#include "app/commands.h"
#include "scenes/scene_registry.h"

namespace raylab::cli {

Runner add_info(CLI::App& app) {
  auto scene_spec = std::make_shared<std::string>("cornell");
  auto positional = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand("info", "print a scene's triangle count, bounds and load time");
  auto* scene_opt = cmd->add_option("--scene", *scene_spec, "procedural scene spec, mesh file or JSON scene file")->capture_default_str();
  cmd->add_option("scene", *positional, "the scene, as for --scene")->excludes(scene_opt);
  return [scene_spec, positional]() {
    Timer t;
    const Scene s = load_scene(positional->empty() ? *scene_spec : *positional);
    const double ms = t.ms();
    const Aabb b = s.bounds();
    size_t emitters = 0;
    for (size_t i = 0; i < s.num_triangles(); ++i) emitters += s.material_of(static_cast<uint32_t>(i)).is_emissive();
    std::printf("scene      %s\ntriangles  %zu\nvertices   %zu\nmaterials  %zu\nemitters   %zu triangles\n", s.name.c_str(),
                s.num_triangles(), s.mesh.num_vertices(), s.materials.size(), emitters);
    if (b.is_empty()) std::printf("bounds     empty\n");
    else
      std::printf("bounds     (%g, %g, %g) .. (%g, %g, %g)\n", b.lo.x(), b.lo.y(), b.lo.z(), b.hi.x(), b.hi.y(), b.hi.z());
    std::printf("view       from (%g, %g, %g) at (%g, %g, %g), fov %g deg, %dx%d\nload       %.1f ms\n", s.view.from.x(),
                s.view.from.y(), s.view.from.z(), s.view.at.x(), s.view.at.y(), s.view.at.z(), s.view.fov_deg,
                s.view.width, s.view.height, ms);
    return 0;
  };
}

Runner add_scenes(CLI::App& app) {
  app.add_subcommand("scenes", "list procedural scenes and their parameters");
  return []() {
    std::printf("%s", describe_scenes().c_str());
    return 0;
  };
}

Runner add_accels(CLI::App& app) {
  app.add_subcommand("accels", "list accelerators and their parameters");
  return []() {
    std::printf("%s", describe_accelerators().c_str());
    return 0;
  };
}

}  // namespace raylab::cli
