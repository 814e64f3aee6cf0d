#include <cstdio>
#include <filesystem>
#include <memory>

#include <fmt/format.h>
#include <tbb/global_control.h>

#include "accel/registry.h"
#include "app/camera_options.h"
#include "app/cmd_render_aov.h"
#include "base/timer.h"
#include "app/commands.h"
#include "app/progress.h"
#include "bench/report.h"
#include "checks/memory_guard.h"
#include "scenes/scene_registry.h"
#include "tracer/integrator.h"

namespace raylab::cli {

namespace {

// out/<name>.png from the scene argument: a file's stem ("bunny" for
// ../shared/scenes/bunny.ply), or the procedural spec with its punctuation
// turned into '_' ("sphereflake_level_2").
std::string default_output_name(const std::string& scene_arg) {
  std::string stem = scene_arg;
  std::error_code ec;
  if (std::filesystem::is_regular_file(scene_arg, ec)) stem = std::filesystem::path(scene_arg).stem().string();
  std::string out;
  for (char c : stem) {
    const bool keep = std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_';
    if (keep) out += c;
    else if (!out.empty() && out.back() != '_') out += '_';
  }
  while (!out.empty() && out.back() == '_') out.pop_back();
  return "out/" + (out.empty() ? std::string("render") : out) + ".png";
}

// The output image: -o as given (its directory must exist), or the default
// out/<name><suffix>.png.
std::string output_image_path(const std::string& given, const std::string& scene_arg, const std::string& suffix) {
  if (!given.empty()) {
    check_output_path(given);
    return given;
  }
  std::string path = default_output_name(scene_arg);
  path.insert(path.size() - 4, suffix);
  return path;
}

struct RenderOpts {
  std::string scene, positional_scene, accel = "bvh", size, out, timings, camera, up, background, aov, aov_scale = "auto";
  int spp = 64, threads = 0, max_depth = 64;
  uint64_t seed = 1;
  bool quiet = false;
};

// Without -o the image goes to out/, created when missing (the one directory
// render makes, as documented), once the scene has loaded.
void make_default_output_directory(const RenderOpts& o, const std::string& path) {
  if (!o.out.empty()) return;
  std::error_code ec;
  std::filesystem::create_directory(std::filesystem::path(path).parent_path(), ec);
  check_output_path(path);
}

// --aov: a per-pixel cost picture of each accelerator instead of a rendering.
int run_cost_aov(const RenderOpts& o, const std::vector<std::string>& accels) {
  check_aov_kind(o.aov);
  check_aov_scale(o.aov_scale);
  AovOptions aov;
  aov.kind = o.aov;
  aov.scale = o.aov_scale;
  aov.accels = accels;
  const std::string scene_arg = pick_scene("render", o.scene, o.positional_scene, "cornell");
  {
    const std::string ext = lower_extension_of(o.out);
    if (!o.out.empty() && ext != ".png" && ext != ".pfm")
      throw std::invalid_argument(fmt::format("-o {}: --aov writes a .png (with the raw .pfm next to it) or a .pfm", o.out));
  }
  if (!o.size.empty()) std::tie(aov.width, aov.height) = parse_size(o.size);
  if (!o.camera.empty()) {
    View probe;
    apply_camera_option(o.camera, probe);
  }
  aov.out = output_image_path(o.out, scene_arg, "_" + o.aov);
  Scene scene = load_scene(scene_arg);
  if (!o.up.empty()) apply_up_axis(o.up, scene);
  if (!o.camera.empty()) apply_camera_option(o.camera, scene.view);
  make_default_output_directory(o, aov.out);
  InterruptGuard interrupt;  // Ctrl-C: stop within a block of pixels, write nothing, exit 130
  aov.stop = interrupt.flag();
  return render_cost_aov(scene, aov);
}

// A path-traced image of the scene with one accelerator.
int run_render(const RenderOpts& o, const std::vector<std::string>& accels) {
  if (accels.size() != 1)
    throw std::invalid_argument(fmt::format(
        "render uses one accelerator, '{}' names {} ({}); lists and 'all' are for verify, stress and bench",
        o.accel, accels.size(), fmt::join(accels, " ")));
  auto accel = make_accelerator(accels.front());
  const std::string scene_arg = pick_scene("render", o.scene, o.positional_scene, "cornell");
  {
    const std::string ext = lower_extension_of(o.out);
    if (!o.out.empty() && ext != ".png" && ext != ".pfm" && ext != ".exr")
      throw std::invalid_argument(fmt::format("-o {}: use a .png, .exr or .pfm file name", o.out));
  }
  if (!o.timings.empty()) check_output_path(o.timings, "--timings");
  std::pair<int, int> size{0, 0};
  if (!o.size.empty()) size = parse_size(o.size);
  const Vec3f background = o.background.empty() ? Vec3f::Zero() : parse_background(o.background);
  if (!o.camera.empty()) {
    View probe;
    apply_camera_option(o.camera, probe);  // syntax errors before the load
  }

  const std::string out = output_image_path(o.out, scene_arg, "");
  Timer load;
  Scene scene = load_scene(scene_arg);
  const double load_ms = load.ms();
  if (!o.up.empty()) apply_up_axis(o.up, scene);
  if (!o.camera.empty()) apply_camera_option(o.camera, scene.view);
  if (!o.up.empty() || !o.camera.empty()) aim_key_light(scene);  // keep the light where it was, relative to the camera
  if (!o.background.empty()) scene.background = background;
  RenderSettings rs;
  rs.width = scene.view.width;
  rs.height = scene.view.height;
  if (!o.size.empty()) std::tie(rs.width, rs.height) = size;
  rs.spp = o.spp;
  rs.seed = o.seed;
  rs.max_depth = o.max_depth;
  rs.progress = !o.quiet && stderr_is_terminal();
  InterruptGuard interrupt;  // Ctrl-C: stop within a batch of paths, write nothing, exit 130
  rs.stop = interrupt.flag();
  require_structure_fits(accel->spec(), scene.mesh);
  Timer wall;
  const BuildStats bs = accel->build(scene.mesh);
  const RenderResult r = render(scene, *accel, rs);
  const double wall_s = wall.seconds();
  if (!r.complete || interrupt.interrupted()) {
    // A partial image would pass for a finished one: none is written.
    std::fprintf(stderr, "raylab render: interrupted after %.1f s: no image written\n", wall_s);
    return kExitInterrupted;
  }
  make_default_output_directory(o, out);
  write_image(r.image, out);
  const double mrays = (r.rays + r.shadow_rays) / std::max(r.seconds, 1e-9) * 1e-6;
  std::printf("%s: %zu triangle%s (loaded in %.1f ms), %s built in %.1f ms, %dx%d at %d spp in %.2f s (%.2f Mrays/s) -> %s\n",
              scene.name.c_str(), scene.num_triangles(), scene.num_triangles() == 1 ? "" : "s", load_ms,
              accel->spec().c_str(), bs.build_ms, rs.width, rs.height, rs.spp, r.seconds, mrays, out.c_str());
  if (!o.timings.empty()) {
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
    write_json_report(o.timings, report_header("render"), nlohmann::json::array({rec}));
  }
  return 0;
}

}  // namespace

Runner add_render(CLI::App& app) {
  auto o = std::make_shared<RenderOpts>();
  CLI::App* cmd = app.add_subcommand("render", "path-trace a scene to PNG, EXR or PFM");
  add_scene_options(cmd, o->positional_scene, o->scene,
                    "the scene: procedural spec, mesh file or JSON scene file (default cornell; see raylab scenes)");
  cmd->add_option("--accel", o->accel, "one accelerator spec (see raylab accels)")->capture_default_str();
  cmd->add_option("-s,--spp", o->spp, "samples per pixel")->capture_default_str()->check(CLI::Range(1, 1 << 20));
  cmd->add_option("--size", o->size, "image size WIDTHxHEIGHT (default: the scene's view)");
  cmd->add_option("-o,--out", o->out,
                  "output image: .png (8-bit sRGB), .exr (linear 32-bit float) or .pfm (linear 32-bit float); "
                  "its directory must exist; default out/<scene name>.png (out/ is created)");
  cmd->add_option("--camera", o->camera,
                  "camera override, any of from=x,y,z,at=x,y,z,up=x,y,z,fov=deg (e.g. --camera from=0,1,4,at=0,0.5,0)");
  cmd->add_option("--up", o->up, "the up axis of a mesh file: x, y, z, -x, -y, -z (Z-up files: --up z); re-frames the camera");
  cmd->add_option("--background", o->background, "radiance of rays leaving the scene: one value (grey) or r,g,b");
  cmd->add_option("--seed", o->seed, "random seed")->capture_default_str();
  add_threads_option(cmd, o->threads);
  cmd->add_option("--max-depth", o->max_depth, "maximum path length")->capture_default_str()->check(CLI::Range(1, 1024));
  cmd->add_option("--timings", o->timings, "also write the timings (build, render, wall time) as a JSON record to this file");
  add_renamed_option(cmd, "--json", "--timings FILE");
  cmd->add_flag("-q,--quiet", o->quiet, "no progress line");
  cmd->add_option("--aov", o->aov,
                  "per-pixel cost picture instead of a rendering: nodes, tris or time per primary ray "
                  "(PNG with colour bar + raw PFM; with several --accel, one contact sheet)");
  cmd->add_option("--aov-scale", o->aov_scale,
                  "colours of --aov: auto (a sheet: one log scale for all tiles; one picture: linear unless its values "
                  "span orders of magnitude), log or linear (one scale for all tiles), each (each tile its own linear "
                  "scale)")
      ->capture_default_str();

  return [o]() {
    std::unique_ptr<tbb::global_control> limit;
    if (o->threads > 0)
      limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, o->threads);
    // Check every argument before loading a possibly large scene.
    const auto accels = expand_accelerator_list(o->accel);
    if (o->aov.empty() && o->aov_scale != "auto")
      throw std::invalid_argument("--aov-scale applies to --aov pictures only");
    return o->aov.empty() ? run_render(*o, accels) : run_cost_aov(*o, accels);
  };
}

}  // namespace raylab::cli
