#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "accel/registry.h"
#include "app/cmd_report_palette.h"
#include "base/timer.h"
#include "app/commands.h"
#include "bench/bench_run.h"
#include "checks/memory_guard.h"
#include "scenes/scene_registry.h"

namespace raylab::cli {

// Builds each accelerator `repeats` times and prints the figures of the
// median build (build time, memory, tree shape and structure-specific extras).
void print_build_stats(const Scene& s, const std::string& accel_list, int repeats) {
  for (const auto& spec : expand_accelerator_list(accel_list)) {
    std::vector<std::pair<double, BuildStats>> runs;
    for (int i = 0; i < repeats; ++i) {
      require_structure_fits(spec, s.mesh);
      auto accel = make_accelerator(spec);
      const BuildStats st = accel->build(s.mesh);
      runs.emplace_back(st.build_ms, st);
    }
    std::sort(runs.begin(), runs.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const BuildStats& st = runs[runs.size() / 2].second;
    // Structures that report no tree shape (Embree, brute) show n/a, not 0 or nan.
    const bool tree = st.nodes > 0 || st.leaves > 0;
    auto or_na = [](bool ok, const std::string& v) { return ok ? v : std::string("n/a"); };
    size_t width = 10;
    for (const auto& [key, value] : st.extra) width = std::max(width, key.size());
    auto row = [&](const std::string& key, const std::string& value) {
      std::printf("  %-*s %s\n", static_cast<int>(width), key.c_str(), value.c_str());
    };
    std::printf("accel      %s\n", spec.c_str());
    row("build_ms", fmt::format("{:.2f} (median of {})", st.build_ms, repeats));
    row("bytes", std::to_string(st.bytes));
    row("nodes", or_na(tree, std::to_string(st.nodes)));
    row("leaves", or_na(tree, std::to_string(st.leaves)));
    row("max_depth", or_na(tree, std::to_string(st.max_depth)));
    row("avg_depth", or_na(tree, fmt::format("{:.2f}", st.avg_depth)));
    row("sah_cost", or_na(std::isfinite(st.sah_cost), fmt::format("{:.4g}", st.sah_cost)));
    for (const auto& [key, value] : st.extra) row(key, fmt::format("{:.6g}", value));
    const std::string warning = depth_cap_warning(st);
    std::fflush(stdout);
    if (!warning.empty()) std::fprintf(stderr, "raylab info: warning: %s: %s\n", spec.c_str(), warning.c_str());
  }
}

Runner add_info(CLI::App& app) {
  auto scene_spec = std::make_shared<std::string>();
  auto positional = std::make_shared<std::string>();
  auto accel_list = std::make_shared<std::string>();
  auto repeats = std::make_shared<int>(1);
  CLI::App* cmd = app.add_subcommand("info", "print a scene's triangle count, bounds and load time");
  add_scene_options(cmd, *positional, *scene_spec, "the scene: procedural spec, mesh file or JSON scene file (default cornell)");
  cmd->add_option("--accel", *accel_list, "also build these accelerators and print their build figures");
  cmd->add_option("--build-repeats", *repeats, "builds per accelerator (median reported)")->check(CLI::Range(1, 100));
  return [scene_spec, positional, accel_list, repeats]() {
    Timer t;
    const Scene s = load_scene(pick_scene("info", *scene_spec, *positional, "cornell"));
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
    if (!accel_list->empty()) print_build_stats(s, *accel_list, *repeats);
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

// A declared parameter: name, default, help, and its valid values as the
// spec parser checks them (kind; `valid` in words; choices or numeric range).
static nlohmann::json param_json(const ParamInfo& p) {
  static const char* const kinds[] = {"text", "integer", "real", "boolean", "choice"};
  const ParamCheck& c = p.check;
  nlohmann::json j = {{"name", p.name}, {"default", p.default_value}, {"help", p.help},
                      {"kind", kinds[static_cast<int>(c.kind)]}, {"valid", c.describe()}};
  if (c.kind == ParamKind::Choice) j["choices"] = c.words;
  if (c.kind == ParamKind::Integer || c.kind == ParamKind::Real) {
    const auto bound = [](double x) { return std::isinf(x) ? nlohmann::json(nullptr) : nlohmann::json(x); };
    const bool real = c.kind == ParamKind::Real;
    if (c.has_range)
      j["range"] = {{"min", bound(c.lo)}, {"max", bound(c.hi)},
                    {"min_open", real && (c.ends == Ends::OpenLow || c.ends == Ends::Open)},
                    {"max_open", real && (c.ends == Ends::OpenHigh || c.ends == Ends::Open)}};
    if (!c.numbers.empty()) j["also_numbers"] = c.numbers;
    if (!c.words.empty()) j["also_words"] = c.words;
  }
  return j;
}

// The registry as JSON, for scripts (scripts/*.sh, bench/plot.py): they ask
// the binary instead of keeping their own lists of structures.
static nlohmann::json accelerators_json() {
  nlohmann::json out = nlohmann::json::array();
  for (const auto& info : accelerator_registry()) {
    nlohmann::json j;
    j["name"] = info.name;
    j["help"] = info.help;
    j["description"] = nullptr;
    if (info.describe) {
      j["description"] = nlohmann::json::object();
      for (const auto& [key, value] : info.describe()) j["description"][key] = value;
    }
    j["params"] = nlohmann::json::array();
    for (const auto& p : info.params) j["params"].push_back(param_json(p));
    j["stats"] = nlohmann::json::array();
    for (const auto& st : info.stats) j["stats"].push_back({{"key", st.key}, {"help", st.help}});
    j["cover"] = info.cover;
    j["build_peak_bytes_per_triangle"] = info.build_peak_bytes_per_triangle;
    const Capabilities& c = info.caps;
    j["capabilities"] = {{"mt_variant", c.mt_variant.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.mt_variant)},
                         {"robust_variant", c.robust_variant.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.robust_variant)},
                         {"scalar_variant", c.scalar_variant.empty() ? nlohmann::json(nullptr) : nlohmann::json(c.scalar_variant)},
                         {"per_ray_counters", c.per_ray_counters},
                         {"quadratic", c.quadratic},
                         {"reference", c.reference},
                         {"outline", c.outline}};
    j["colour"] = structure_colour_of_name(info.name);  // one colour per structure in every chart
    out.push_back(j);
  }
  return out;
}

Runner add_accels(CLI::App& app) {
  auto* cmd = app.add_subcommand("accels", "list accelerators and their parameters");
  auto json = std::make_shared<bool>(false);
  cmd->add_flag("--json", *json, "the registry as JSON (capabilities, parameters, statistics, specs to cover)");
  return [json]() {
    if (*json) std::printf("%s\n", accelerators_json().dump(2).c_str());
    else std::printf("%s", describe_accelerators().c_str());
    return 0;
  };
}

}  // namespace raylab::cli
