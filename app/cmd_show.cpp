// `raylab show`: a picture of an acceleration structure itself. The
// structure's outline (Accelerator::outline: BVH boxes at a depth, k-d split
// planes, occupied grid cells) is written as a wireframe for any viewer
// (.ply, .obj) and/or drawn over an eye-light shading of the scene (.png).
#include <cstdio>
#include <memory>

#include <fmt/format.h>

#include "accel/registry.h"
#include "app/camera_options.h"
#include "app/cmd_show_draw.h"
#include "app/commands.h"
#include "checks/memory_guard.h"
#include "scenes/scene_registry.h"

namespace raylab::cli {

namespace {
// Four levels: enough to see how a structure divides the scene, few enough
// that the lines do not blend into a haze (the study's pictures use it too).
constexpr int kDefaultShowDepth = 4;
// Without --size the picture is the scene's view, at least this wide (the
// labels and the depth legend need the room).
constexpr int kMinDefaultWidth = 480;
}  // namespace

Runner add_show(CLI::App& app) {
  struct Opts {
    std::string scene, positional_scene, accel = "bvh", size, camera, up;
    std::vector<std::string> outs;
    int depth = kDefaultShowDepth;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "show", "picture of a structure: its boxes / split planes / cells as a .ply or .obj wireframe, or drawn over the scene (.png)");
  cmd->add_option("scene", o->positional_scene, "the scene (default cornell; see raylab scenes)");
  cmd->add_option("--scene", o->scene, "the scene, as the positional argument");
  cmd->add_option("--accel", o->accel, "one accelerator spec (see raylab accels)")->capture_default_str();
  cmd->add_option("-d,--depth", o->depth, "deepest structure level drawn (0 = the root)")
      ->capture_default_str()
      ->check(CLI::Range(0, 64));
  cmd->add_option("-o,--out", o->outs,
                  "output file(s), repeatable, each directory must exist: .png (overlay on the scene with a title and "
                  "a depth legend), .pfm (the overlay alone), .ply or .obj (wireframe)")
      ->required();
  cmd->add_option("--size", o->size,
                  fmt::format("overlay size WIDTHxHEIGHT (default: the scene's view, at least {} pixels wide)",
                              kMinDefaultWidth));
  cmd->add_option("--camera", o->camera, "camera override, as for render (from=x,y,z,at=x,y,z,up=x,y,z,fov=deg)");
  cmd->add_option("--up", o->up, "the up axis of a mesh file, as for render");

  return [o]() {
    // Every argument is checked before the scene is loaded.
    const auto accels = expand_accelerator_list(o->accel);
    if (accels.size() != 1)
      throw std::invalid_argument(fmt::format("show draws one accelerator, '{}' names {}", o->accel, accels.size()));
    for (const auto& out : o->outs) {
      const std::string ext = lower_extension_of(out);
      if (ext != ".png" && ext != ".pfm" && ext != ".ply" && ext != ".obj")
        throw std::invalid_argument(fmt::format("-o {}: use a .png or .pfm (overlay), .ply or .obj (wireframe) file name", out));
      check_output_path(out);
    }
    std::pair<int, int> size{0, 0};
    if (!o->size.empty()) size = parse_size(o->size);
    if (!o->camera.empty()) {
      View probe;
      apply_camera_option(o->camera, probe);
    }
    auto accel = make_accelerator(accels.front());
    const bool draws = accelerator_info(Spec::parse(accels.front()).name).caps.outline;

    Scene scene = load_scene(pick_scene("show", o->scene, o->positional_scene, "cornell"));
    if (!o->up.empty()) apply_up_axis(o->up, scene);
    if (!o->camera.empty()) apply_camera_option(o->camera, scene.view);
    require_structure_fits(accel->spec(), scene.mesh);
    accel->build(scene.mesh);
    StructureOutline outline;
    accel->outline(o->depth, outline);
    if (!draws)
      std::fprintf(stderr, "raylab show: note: %s does not expose its structure; drawing %s\n", accel->spec().c_str(),
                   outline.what.empty() ? "nothing" : outline.what.c_str());
    if (outline.truncated)
      std::fprintf(stderr, "raylab show: warning: the outline was cut at %zu elements (use a smaller --depth)\n",
                   outline.size());
    for (const auto& out : o->outs) {
      const std::string ext = lower_extension_of(out);
      if (ext == ".png" || ext == ".pfm") {
        int w = scene.view.width, h = scene.view.height;
        if (!o->size.empty()) {
          std::tie(w, h) = size;
        } else if (w < kMinDefaultWidth) {
          h = std::max(1, h * kMinDefaultWidth / std::max(1, w));
          w = kMinDefaultWidth;
        }
        Image img = shade_scene(scene, *accel, w, h);
        draw_outline(img, ViewProjector(scene.view, w, h), outline);
        // The PNG carries the title (the spec and what its layout draws, e.g.
        // "BVH8 node boxes") and the depth colours; the PFM is the overlay alone.
        if (ext == ".png") {
          const std::string title = fmt::format("{}: {}, depth 0 to {}", accel->spec(), outline.what,
                                                std::max(0, outline.max_depth()));
          img = structure_picture(img, title, std::max(0, outline.max_depth()));
        }
        write_image(img, out);
      } else {
        write_outline_wireframe(outline, out);
      }
    }
    std::printf("%s: %s, %zu boxes, %zu planes, %zu segments (depth <= %d) -> %s\n", scene.name.c_str(),
                accel->spec().c_str(), outline.boxes.size(), outline.quads.size(), outline.segments.size(), o->depth,
                fmt::format("{}", fmt::join(o->outs, ", ")).c_str());
    return 0;
  };
}

}  // namespace raylab::cli
