#include <unistd.h>

#include <cstdio>
#include <memory>

#include <fmt/format.h>
#include <tbb/global_control.h>

#include "accel/registry.h"
#include "base/timer.h"
#include "app/commands.h"
#include "bench/report.h"
#include "scenes/scene_registry.h"
#include "tracer/integrator.h"

namespace raylab::cli {

Runner add_render(CLI::App& app) {
  struct Opts {
    std::string scene = "cornell", positional_scene, accel = "bvh", size, out, json;
    int spp = 64, threads = 0, max_depth = 64;
    uint64_t seed = 1;
    bool quiet = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand("render", "path-trace a scene to PNG (or PFM)");
  auto* scene_opt = cmd->add_option("--scene", o->scene, "procedural scene spec, mesh file or JSON scene file")->capture_default_str();
  cmd->add_option("scene", o->positional_scene, "the scene, as for --scene (e.g. scenes/examples/cornell_flake.json)")
      ->excludes(scene_opt);
  cmd->add_option("--accel", o->accel, "accelerator spec")->capture_default_str();
  cmd->add_option("--spp", o->spp, "samples per pixel")->capture_default_str()->check(CLI::Range(1, 1 << 20));
  cmd->add_option("--size", o->size, "image size WIDTHxHEIGHT (default: the scene's view)");
  cmd->add_option("--out", o->out, "output image, .png or .pfm (default: out/<scene>.png)");
  cmd->add_option("--seed", o->seed, "random seed")->capture_default_str();
  cmd->add_option("--threads", o->threads, "worker threads (0 = all cores)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--max-depth", o->max_depth, "maximum path length")->capture_default_str()->check(CLI::Range(1, 1024));
  cmd->add_option("--json", o->json, "also write the timings (build, render, wall time) to this JSON file");
  cmd->add_flag("--quiet", o->quiet, "no progress line");

  return [o]() {
    std::unique_ptr<tbb::global_control> limit;
    if (o->threads > 0)
      limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, o->threads);
    auto accel = make_accelerator(o->accel);  // check the spec before loading a large scene
    Timer load;
    const Scene scene = load_scene(o->positional_scene.empty() ? o->scene : o->positional_scene);
    const double load_ms = load.ms();
    RenderSettings rs;
    rs.width = scene.view.width;
    rs.height = scene.view.height;
    if (!o->size.empty()) std::tie(rs.width, rs.height) = parse_size(o->size);
    rs.spp = o->spp;
    rs.seed = o->seed;
    rs.max_depth = o->max_depth;
    rs.progress = !o->quiet && isatty(fileno(stderr));
    std::string out = o->out;
    if (out.empty()) {
      std::string stem = scene.name;
      for (char& c : stem)
        if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
      out = "out/" + stem + ".png";
    }
    {
      const std::string ext = out.size() >= 4 ? out.substr(out.size() - 4) : "";
      if (ext != ".png" && ext != ".pfm") throw std::invalid_argument(fmt::format("--out {}: use a .png or .pfm file name", out));
    }
    Timer wall;
    const BuildStats bs = accel->build(scene.mesh);
    const RenderResult r = render(scene, *accel, rs);
    const double wall_s = wall.seconds();
    write_image(r.image, out);
    const double mrays = (r.rays + r.shadow_rays) / std::max(r.seconds, 1e-9) * 1e-6;
    std::printf("%s: %zu triangles (loaded in %.1f ms), %s built in %.1f ms, %dx%d at %d spp in %.2f s (%.2f Mrays/s) -> %s\n",
                scene.name.c_str(), scene.num_triangles(), load_ms, accel->spec().c_str(), bs.build_ms, rs.width,
                rs.height, rs.spp, r.seconds, mrays, out.c_str());
    if (!o->json.empty()) {
      const nlohmann::json rec = {{"scene", scene.name},
                                  {"triangles", scene.num_triangles()},
                                  {"accel", accel->spec()},
                                  {"width", rs.width},
                                  {"height", rs.height},
                                  {"spp", rs.spp},
                                  {"seed", rs.seed},
                                  {"build_ms", bs.build_ms},
                                  {"render_s", r.seconds},
                                  {"wall_s", wall_s},
                                  {"rays", r.rays},
                                  {"shadow_rays", r.shadow_rays},
                                  {"mrays_per_s", mrays},
                                  {"image", out}};
      write_json_report(o->json, report_header("render"), nlohmann::json::array({rec}));
    }
    return 0;
  };
}

}  // namespace raylab::cli
