#include "app/cmd_render_aov.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "accel/registry.h"
#include "app/cmd_show_draw.h"
#include "app/commands.h"
#include "checks/memory_guard.h"
#include "tracer/ray_sets.h"

namespace raylab::cli {

namespace {

const char* aov_label(const std::string& kind) {
  if (kind == "nodes") return "nodes/cells per ray";
  if (kind == "tris") return "tri tests per ray";
  return "ns per ray";
}

// Per-pixel cost of one built structure; empty when the structure cannot
// count (Embree has no per-ray counters).
std::vector<float> pixel_costs(const Accelerator& accel, const RaySet& primary, const std::string& kind, int repeats,
                               const std::atomic<bool>* stop) {
  std::vector<float> cost(primary.rays.size(), 0.0f);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, cost.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
    if (stop && stop->load(std::memory_order_relaxed)) return;
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const std::span<const Ray> ray(&primary.rays[i], 1);
      Hit hit;
      if (kind == "time") {
        // Minimum over repeats: the least disturbed measurement of this ray.
        double best = 1e300;
        for (int k = 0; k < repeats; ++k) {
          const auto t0 = std::chrono::steady_clock::now();
          accel.intersect(ray, std::span<Hit>(&hit, 1));
          const auto t1 = std::chrono::steady_clock::now();
          best = std::min(best, std::chrono::duration<double, std::nano>(t1 - t0).count());
        }
        cost[i] = static_cast<float>(best);
      } else {
        TraversalStats st;
        accel.intersect(ray, std::span<Hit>(&hit, 1), &st);
        cost[i] = static_cast<float>(kind == "nodes" ? st.nodes_visited : st.triangle_tests);
      }
    }
  });
  return cost;
}

void write_raw(const std::vector<float>& cost, int w, int h, const std::string& path) {
  Image raw(w, h);
  for (size_t i = 0; i < cost.size(); ++i) raw.rgb[3 * i] = raw.rgb[3 * i + 1] = raw.rgb[3 * i + 2] = cost[i];
  write_image(raw, path);
}

std::string file_safe(const std::string& spec) {
  std::string s;
  for (char c : spec) s += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return s;
}

double mean_of(const std::vector<float>& v) {
  double s = 0.0;
  for (float x : v) s += x;
  return v.empty() ? 0.0 : s / static_cast<double>(v.size());
}

}  // namespace

void check_aov_kind(const std::string& kind) {
  if (kind != "nodes" && kind != "tris" && kind != "time")
    throw std::invalid_argument(fmt::format("--aov {}: use nodes, tris or time", kind));
}

void check_aov_scale(const std::string& scale) {
  if (scale != "auto" && scale != "log" && scale != "linear" && scale != "each")
    throw std::invalid_argument(fmt::format("--aov-scale {}: use auto, log, linear or each", scale));
}

int render_cost_aov(const Scene& scene, const AovOptions& o) {
  check_aov_kind(o.kind);
  const int w = o.width > 0 ? o.width : scene.view.width;
  const int h = o.height > 0 ? o.height : scene.view.height;
  const RaySet primary = make_primary_rays(scene, w, h);
  const bool png = lower_case_extension(o.out) == ".png";
  const std::filesystem::path out(o.out);
  struct Result {
    std::string spec;
    std::vector<float> cost;  // empty: no counters
  };
  std::vector<Result> results;
  auto stopped = [&] { return o.stop && o.stop->load(); };
  for (const auto& spec : o.accels) {
    if (stopped()) break;
    auto accel = make_accelerator(spec);
    const bool counts = accelerator_info(Spec::parse(spec).name).caps.per_ray_counters;
    require_structure_fits(spec, scene.mesh);
    accel->build(scene.mesh);
    Result r{accel->spec(), {}};
    if (o.kind == "time" || counts) r.cost = pixel_costs(*accel, primary, o.kind, o.time_repeats, o.stop);
    if (stopped()) break;
    if (r.cost.empty()) {
      std::printf("%s: %s has no per-ray counters (no %s picture)\n", scene.name.c_str(), r.spec.c_str(), o.kind.c_str());
    } else {
      const float max = *std::max_element(r.cost.begin(), r.cost.end());
      std::printf("%s: %s %s per ray: mean %.2f, max %.0f\n", scene.name.c_str(), r.spec.c_str(), o.kind.c_str(),
                  mean_of(r.cost), max);
    }
    results.push_back(std::move(r));
  }
  if (stopped()) {
    std::fprintf(stderr, "raylab render: interrupted: no picture written\n");
    return kExitInterrupted;
  }
  const bool sheet = results.size() > 1;
  // Raw values: <out>.pfm for one structure, <stem>.<spec>.pfm for a sheet.
  std::vector<float> all;
  for (const auto& r : results) {
    if (r.cost.empty()) continue;
    all.insert(all.end(), r.cost.begin(), r.cost.end());
    std::filesystem::path raw = out;
    if (sheet) raw.replace_filename(out.stem().string() + "." + file_safe(r.spec) + ".pfm");
    else raw.replace_extension(".pfm");
    write_raw(r.cost, w, h, raw.string());
  }
  if (!png) return 0;
  // One scale for every tile (comparable colours), unless each tile gets its own.
  const bool each = o.scale == "each";
  const ScaleKind kind = o.scale == "log" || (o.scale == "auto" && sheet) ? ScaleKind::Log
                         : o.scale == "auto"                              ? ScaleKind::Auto
                                                                          : ScaleKind::Linear;
  const CostScale shared = fit_cost_scale(all, kind);
  // The legend says which scale the colours are on.
  std::string label = aov_label(o.kind);
  if (sheet && each) label += ", this tile's own scale";
  else if (sheet) label += shared.log ? ", one log scale for all tiles" : ", one scale for all tiles";
  else if (shared.log) label += " (log scale)";
  int title_rows = 0;
  for (const auto& r : results)
    title_rows = std::max(title_rows, static_cast<int>(wrap_text(r.spec, w - 12, label_size_for(w)).size()));
  std::vector<Image> tiles;
  for (const auto& r : results) {
    const std::string title = sheet ? r.spec : std::string();
    // A structure without counters gets a grey tile saying so (empty values), not a black one that reads as "no work".
    const CostScale scale = each && !r.cost.empty() ? fit_cost_scale(r.cost, ScaleKind::Linear) : shared;
    tiles.push_back(cost_picture(r.cost, w, h, scale, label, title, sheet ? title_rows : 0));
  }
  const int columns = static_cast<int>(std::ceil(std::sqrt(static_cast<double>(tiles.size()))));
  write_image(sheet ? contact_sheet(tiles, columns) : tiles.front(), o.out);
  std::printf("-> %s (colours: %s)\n", o.out.c_str(),
              each ? "each tile its own linear scale"
                   : fmt::format("{}{} scale, 0 to {:.4g}", sheet ? "one " : "", shared.log ? "log" : "linear",
                                 shared.hi)
                         .c_str());
  return 0;
}

}  // namespace raylab::cli
