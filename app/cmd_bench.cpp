#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <set>

#include <fmt/format.h>

#include "accel/registry.h"
#include "base/atomic_file.h"
#include "app/commands.h"
#include "app/progress.h"
#include "bench/bench_run.h"
#include "bench/embree_selfcheck.h"
#include "bench/ray_file.h"
#include "bench/report.h"
#include "tracer/trace.h"
#include "scenes/scene_registry.h"

namespace raylab::cli {

namespace {

// Presets: defaults for every option not given on the command line.
struct Preset {
  std::string scenes, accel, rays, threads, size;
  size_t random_rays;
  int repeats, build_repeats;
  size_t brute_max_tris;
};

// The real meshes as researchers see them: the bunny as framed by
// its file, Sponza and the conference room from inside with lights inside
// (scenes/shared/*.json); full adds a second Sponza view and the dragon in Sponza. Only when run from
// the checkout with ../shared/scenes beside it (`make bench` does), else "".
std::string interior_view_scenes(bool full) {
  namespace fs = std::filesystem;
  if (!fs::exists("scenes/shared/sponza.json") || !fs::exists("../shared/scenes/sponza.ply")) return "";
  std::string s = ";../shared/scenes/bunny.ply;scenes/shared/sponza.json;scenes/shared/conference.json";
  if (full) s += ";scenes/shared/sponza_aisle.json;scenes/shared/dragon_in_sponza.json";
  return s;
}

Preset find_preset(const std::string& name) {
  const std::string all_threads = hardware_threads() > 1 ? fmt::format("1,{}", hardware_threads()) : "1";
  if (name == "quick")
    return {"cornell;terrain:n=96;sphereflake:level=2,segments=12" + interior_view_scenes(false), "all;bvh:layout=bvh2,tri=mt",
            "primary,diffuse,shadow,random", all_threads, "192x192", 49152, 5, 3, 5000};
  if (name == "full")
    return {"cornell;terrain:n=256;sphereflake:level=3;city;grass;soup:n=100000" + interior_view_scenes(true),
            "all;bvh:layout=bvh2,tri=mt", "primary,diffuse,shadow,random", all_threads, "512x512", 262144, 7, 3, 5000};
  throw std::invalid_argument(fmt::format("unknown preset '{}' (presets: quick, full)", name));
}

// "FAMILY:PARAM=v1,v2,..." (fixed parameters may precede PARAM:
// "sphereflake:segments=8,level=1,2,3") -> one scene spec per value.
std::vector<std::string> expand_scale(const std::string& text) {
  const auto colon = text.find(':');
  const auto eq = text.rfind('=');
  if (colon == std::string::npos || eq == std::string::npos || eq < colon)
    throw std::invalid_argument(fmt::format("--scale {}: expected FAMILY:PARAM=v1,v2,... (e.g. soup:n=1000,10000)", text));
  const std::string head = text.substr(0, eq);  // "family:fixed=1,param"
  const auto last_comma = head.rfind(',');
  const std::string param = head.substr(last_comma == std::string::npos || last_comma < colon ? colon + 1 : last_comma + 1);
  const std::string prefix = head.substr(0, head.size() - param.size());  // "family:" or "family:fixed=1,"
  const auto values = parse_name_list(text.substr(eq + 1));
  if (param.empty() || values.empty())
    throw std::invalid_argument(fmt::format("--scale {}: expected FAMILY:PARAM=v1,v2,... (e.g. soup:n=1000,10000)", text));
  std::vector<std::string> out;
  for (const auto& v : values) out.push_back(prefix + param + "=" + v);
  return out;
}

std::string csv_path_for(const std::string& json) {
  const auto dot = json.rfind('.');
  const auto slash = json.rfind('/');
  if (dot != std::string::npos && (slash == std::string::npos || dot > slash)) return json.substr(0, dot) + ".csv";
  return json + ".csv";
}

struct BenchCli {
  std::string accel = "embree;bvh", ray_sets = "primary,random", threads, size = "512x512", out, csv, preset, ray_file;
  std::vector<std::string> scenes, positional_scenes, scales, sweeps;
  size_t random_rays = 262144, brute_max_tris = 0;
  double memory_headroom = 0.95, min_time = kDefaultMinTimeS;
  int repeats = 5, build_repeats = 1;
  uint64_t seed = 1;
  bool quiet = false, selfcheck = false;
};

// --preset: its values for the options not given; then the default threads.
void apply_preset(BenchCli& o, const CLI::App& cmd) {
  if (!o.preset.empty()) {
    const Preset p = find_preset(o.preset);
    auto unset = [&](const char* name) { return cmd.count(name) == 0; };
    if (unset("--scene") && unset("--scale") && o.positional_scenes.empty()) o.scenes = {p.scenes};
    if (unset("--accel")) o.accel = p.accel;
    if (unset("--ray-sets")) o.ray_sets = p.rays;
    if (unset("--threads")) o.threads = p.threads;
    if (unset("--size")) o.size = p.size;
    if (unset("--rays")) o.random_rays = p.random_rays;
    if (unset("--repeats")) o.repeats = p.repeats;
    if (unset("--build-repeats")) o.build_repeats = p.build_repeats;
    if (unset("--brute-max-tris")) o.brute_max_tris = p.brute_max_tris;
  }
  if (o.threads.empty()) o.threads = hardware_threads() > 1 ? fmt::format("1,{}", hardware_threads()) : "1";
}

// --accel expanded, then every --sweep applied.
std::vector<std::string> accel_specs_of(const BenchCli& o) {
  auto specs = expand_accelerator_list(o.accel);
  for (const auto& sweep : o.sweeps) {
    const auto eq = sweep.find('=');
    if (eq == std::string::npos || eq == 0)
      throw std::invalid_argument(fmt::format("--sweep {}: expected PARAM=v1,v2,...", sweep));
    specs = apply_sweep(specs, sweep.substr(0, eq), parse_name_list(sweep.substr(eq + 1)));
  }
  return specs;
}

// Positional scenes, --scene lists and --scale expansions; cornell when none.
std::vector<std::string> scene_specs_of(const BenchCli& o) {
  std::vector<std::string> scene_specs = o.positional_scenes;
  for (const auto& s : o.scenes)
    for (const auto& one : split_spec_list(s)) scene_specs.push_back(one);
  for (const auto& s : o.scales)
    for (const auto& one : expand_scale(s)) scene_specs.push_back(one);
  if (scene_specs.empty()) scene_specs.push_back("cornell");
  return scene_specs;
}

// --embree-selfcheck: the adapter against a direct Embree loop, no other timing.
int run_embree_selfcheck(const BenchCli& o, const std::vector<std::string>& scene_specs,
                         const std::vector<RaySet>& file_sets) {
  RaySetOptions rso;
  std::tie(rso.width, rso.height) = parse_size(o.size);
  rso.random_count = o.random_rays;
  rso.seed = o.seed;
  const auto names = parse_name_list(o.ray_sets);
  std::vector<SelfCheckRow> rows;
  for (const auto& spec : scene_specs) {
    const Scene scene = load_scene(spec);
    const auto r = file_sets.empty() ? embree_selfcheck(scene, names, rso, o.repeats)
                                     : embree_selfcheck_sets(scene, file_sets, o.repeats);
    rows.insert(rows.end(), r.begin(), r.end());
    if (!o.quiet) std::fprintf(stderr, "selfcheck %s done\n", scene.name.c_str());
  }
  std::printf("embree self-check: adapter (as raylab bench times it) vs direct rtcIntersect1/rtcOccluded1 loop, "
              "Mrays/s, 1 thread, median of %d\n%s",
              o.repeats, format_selfcheck_table(rows).c_str());
  if (!o.out.empty()) {
    nlohmann::json recs = nlohmann::json::array();
    for (const auto& r : rows)
      recs.push_back({{"scene", r.scene}, {"ray_set", r.ray_set}, {"rays", r.rays},
                      {"adapter_mrays_per_s", r.adapter_mrays_per_s}, {"direct_mrays_per_s", r.direct_mrays_per_s},
                      {"ratio_adapter_to_direct", r.ratio}, {"identical", r.identical}, {"prepare_ms", r.prepare_ms}});
    write_json_report(o.out, report_header("bench --embree-selfcheck"), recs);
  }
  bool identical = true;
  for (const auto& r : rows) identical &= r.identical;
  return identical ? 0 : kExitCheckFailed;
}

int run_bench_command(BenchCli& o, const CLI::App& cmd);

}  // namespace

Runner add_bench(CLI::App& app) {
  auto o = std::make_shared<BenchCli>();
  CLI::App* cmd = app.add_subcommand("bench", "time accelerators on the same rays, as ratios to Embree");
  cmd->add_option("scene", o->positional_scenes,
                  "scenes: procedural specs, mesh files or JSON scene files (several allowed; default cornell)");
  cmd->add_option("--scene", o->scenes,
                  "scene specs or mesh files (repeatable; ';' or ',' separated lists), as the positional arguments");
  cmd->add_option("--scale", o->scales,
                  "FAMILY:PARAM=v1,v2,...: one scene per value of a size parameter, e.g. soup:n=1000,10000 (repeatable)");
  cmd->add_option("--preset", o->preset,
                  "quick or full: defaults for the options not given (run from the checkout, the scenes include the "
                  "interior views of scenes/shared when ../shared/scenes is present)");
  add_accel_list_option(cmd, o->accel);
  cmd->add_option("--ray-sets", o->ray_sets, "ray sets, comma separated: primary, diffuse, shadow, random")
      ->capture_default_str();
  cmd->add_option("-t,--threads", o->threads, "thread counts, comma separated, 0 = all cores (default: 1 and all cores)");
  cmd->add_option("--size", o->size, "primary rays: image size WIDTHxHEIGHT")->capture_default_str();
  add_ray_count_option(cmd, o->random_rays, "rays per generated set (random; primary rays are one per pixel of --size)",
                       "--rays");
  cmd->add_option("--repeats", o->repeats, "timed trace repeats (median, min and max reported)")->capture_default_str()->check(CLI::Range(1, 1000));
  cmd->add_option("--min-time", o->min_time,
                  "seconds each timed repeat lasts at least: the set is traced as many times as that takes (as Google "
                  "Benchmark's --benchmark_min_time); 0 = one trace per repeat")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 60.0));
  cmd->add_option("--build-repeats", o->build_repeats, "builds per accelerator (median reported)")->capture_default_str()->check(CLI::Range(1, 100));
  cmd->add_option("--brute-max-tris", o->brute_max_tris, "skip brute on scenes with more triangles (0 = never skip)")->capture_default_str();
  cmd->add_option("--seed", o->seed, "random seed")->capture_default_str();
  cmd->add_option("--memory-headroom", o->memory_headroom,
                  "skip a structure whose estimated peak memory exceeds this share of the available memory (0 = never)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--sweep", o->sweeps, "PARAM=v1,v2,...: one run per value for every accelerator with PARAM (repeatable)");
  cmd->add_option("-o,--out", o->out, "the JSON report (rewritten after every cell; complete false until the run ends)");
  cmd->add_option("--csv", o->csv, "the records as CSV (default: next to the JSON report, .csv)");
  add_renamed_option(cmd, "--json", "-o/--out FILE");
  add_renamed_option(cmd, "--random-rays", "--rays N");
  cmd->add_flag("-q,--quiet", o->quiet, "no progress line");
  cmd->add_option("--ray-file", o->ray_file,
                  "trace the rays of this ray file (raylab rays, docs/ray-file.md) instead of --ray-sets; needs one scene");
  cmd->add_flag("--embree-selfcheck", o->selfcheck,
                "time the embree accelerator against a plain rtcIntersect1/rtcOccluded1 loop on the same prepared rays "
                "(one thread, thread CPU time, median of --repeats) and print the ratios; no other timing");

  return [o, cmd]() { return run_bench_command(*o, *cmd); };
}

namespace {

// The run's options from the command line (and the rays of --ray-file).
BenchOptions bench_options_of(const BenchCli& o, const std::vector<RaySet>& file_sets) {
  BenchOptions bo;
  bo.ray_sets = parse_name_list(o.ray_sets);
  bo.threads = parse_thread_list(o.threads);
  std::tie(bo.width, bo.height) = parse_size(o.size);
  bo.random_rays = o.random_rays;
  bo.repeats = o.repeats;
  bo.min_time_s = o.min_time;
  bo.build_repeats = o.build_repeats;
  bo.brute_max_triangles = o.brute_max_tris;
  bo.seed = o.seed;
  bo.memory_headroom = o.memory_headroom;
  bo.given_sets = file_sets;
  if (!file_sets.empty()) bo.ray_sets = {file_sets.front().name};
  return bo;
}

// The report's header: what ran, with which options.
nlohmann::json bench_report_header(const BenchCli& o, const std::vector<std::string>& scene_specs,
                                   const std::vector<std::string>& specs, const BenchOptions& bo) {
  nlohmann::json header = report_header("bench");
  header["preset"] = o.preset.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.preset);
  header["options"] = {{"scenes", scene_specs},     {"accels", specs},         {"ray_sets", bo.ray_sets},
                       {"threads", bo.threads},     {"size", o.size},         {"random_rays", bo.random_rays},
                       {"repeats", bo.repeats},     {"min_time_s", bo.min_time_s},
                       {"build_repeats", bo.build_repeats},
                       {"brute_max_tris", bo.brute_max_triangles}, {"seed", bo.seed},
                       {"ray_file", o.ray_file.empty() ? nlohmann::json(nullptr) : nlohmann::json(o.ray_file)}};
  return header;
}

// What a bench run has produced so far: its records and skips, written to
// the JSON and CSV files after every cell (an interrupted run keeps them).
struct BenchOutput {
  std::string json_path, csv_path;
  nlohmann::json header;
  std::vector<BenchRecord> records;
  std::vector<BenchSkip> skipped;

  void save(bool complete) const {
    if (!json_path.empty()) {
      nlohmann::json recs = nlohmann::json::array();
      for (const auto& r : records) recs.push_back(r.to_json());
      nlohmann::json h = header;
      h["complete"] = complete;
      h["skipped"] = nlohmann::json::array();
      for (const auto& s : skipped) h["skipped"].push_back(s.to_json());
      write_json_report(json_path, h, recs);
    }
    if (!csv_path.empty()) write_file_atomically(csv_path, bench_csv(records));
  }
};

// Where a scene's cells stand, for the progress line and the per-cell lines.
struct SceneProgress {
  size_t scene_index = 0, scenes = 0, cells = 0, done = 0;
  std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();

  std::string prefix() const {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::string eta =
        done > 0 && cells > done ? fmt::format(", ~{} left in this scene", format_duration(elapsed / done * (cells - done)))
                                 : std::string();
    return fmt::format("[scene {}/{}, cell {}/{}, {}{}]", scene_index + 1, scenes, done + 1, cells,
                       format_duration(elapsed), eta);
  }
};

// Times every structure on one scene, appending its records and skips to out.
void bench_scene(const std::string& spec, const std::vector<std::string>& specs, const BenchOptions& bo,
                 SceneProgress sp, bool show, BenchOutput& out) {
  const bool tty = show && isatty(fileno(stderr));
  if (tty) std::fprintf(stderr, "\r\033[Kloading %s", spec.c_str());
  const Scene scene = load_scene(spec);
  const auto cell_specs = bench_specs_for_scene(specs, scene.num_triangles(), bo);
  sp.cells = cell_specs.size() * bo.ray_sets.size() * bo.threads.size();
  if (show && cell_specs.size() < specs.size())
    std::fprintf(stderr, "%sbench: %s: brute skipped (%zu triangles > --brute-max-tris %zu)\n", tty ? "\r\033[K" : "",
                 scene.name.c_str(), scene.num_triangles(), bo.brute_max_triangles);
  BenchProgress progress;
  if (tty)
    progress = [&](const std::string& m) {
      std::fprintf(stderr, "\r\033[K%s %s", sp.prefix().c_str(), m.c_str());
      std::fflush(stderr);
    };
  std::set<std::string> noted;
  const size_t primary_rays = static_cast<size_t>(bo.width) * bo.height;
  const auto on_record = [&](const BenchRecord& r) {
    ++sp.done;
    out.records.push_back(r);
    out.save(false);
    const size_t asked = r.ray_set == "random" ? bo.random_rays : primary_rays;
    if (show && r.rays != asked && noted.insert(r.ray_set).second)
      std::fprintf(stderr, "%s%s: %s", tty ? "\r\033[K" : "", r.scene.c_str(),
                   ray_set_size_note(r.ray_set, asked, r.rays).c_str());
    if (show && !tty)
      std::fprintf(stderr, "bench [scene %zu/%zu, cell %zu/%zu] %s %s %s t=%d: %.2f Mrays/s, %.3f x embree\n",
                   sp.scene_index + 1, sp.scenes, sp.done, sp.cells, r.scene.c_str(), r.accel.c_str(),
                   r.ray_set.c_str(), r.threads, r.mrays_per_s, r.ratio_to_embree);
  };
  const auto on_skip = [&](const BenchSkip& skip) {
    out.skipped.push_back(skip);
    out.save(false);
    std::printf("bench %s: %s skipped: %s\n", skip.scene.c_str(), skip.accel.c_str(), skip.reason.c_str());
  };
  const auto records = run_bench(scene, specs, bo, progress, on_record, on_skip);
  // The returned records carry the best-Embree figures of the whole run.
  if (out.records.size() >= records.size()) {
    std::copy(records.begin(), records.end(), out.records.end() - static_cast<std::ptrdiff_t>(records.size()));
    out.save(false);
  }
  if (tty) std::fprintf(stderr, "\r\033[K");
  std::printf("bench %s (%zu triangles)\n%s", scene.name.c_str(), scene.num_triangles(),
              format_bench_table(records).c_str());
  std::printf("%s", format_build_summary(records).c_str());
  std::printf("%s", format_embree_noise(embree_noise(records)).c_str());
  std::fflush(stdout);
  std::fputs(bench_short_repeat_warning(records).c_str(), stderr);
}

int run_bench_command(BenchCli& o, const CLI::App& cmd) {
  apply_preset(o, cmd);
  const std::vector<std::string> specs = accel_specs_of(o);
  const std::vector<std::string> scene_specs = scene_specs_of(o);
  std::vector<RaySet> file_sets;
  if (!o.ray_file.empty()) {
    if (scene_specs.size() != 1)
      throw std::invalid_argument("--ray-file: give exactly one scene (the scene the rays were made for)");
    if (cmd.count("--ray-sets")) throw std::invalid_argument("--ray-file replaces --ray-sets: give one of them");
    file_sets.push_back(read_ray_file(o.ray_file).set);
  }

  if (!o.out.empty()) check_output_path(o.out);
  if (!o.csv.empty()) check_output_path(o.csv, "--csv");
  if (o.selfcheck) return run_embree_selfcheck(o, scene_specs, file_sets);

  BenchOptions bo = bench_options_of(o, file_sets);
  BenchOutput out;
  out.json_path = o.out;
  out.csv_path = !o.csv.empty() ? o.csv : (o.out.empty() ? std::string() : csv_path_for(o.out));
  out.header = bench_report_header(o, scene_specs, specs, bo);

  InterruptGuard interrupt;  // Ctrl-C: finish the current cell, keep the records
  bo.stop = interrupt.flag();
  for (size_t i = 0; i < scene_specs.size() && !interrupt.interrupted(); ++i) {
    SceneProgress sp;
    sp.scene_index = i;
    sp.scenes = scene_specs.size();
    bench_scene(scene_specs[i], specs, bo, sp, !o.quiet, out);
  }
  const bool interrupted = interrupt.interrupted();
  out.save(!interrupted);
  if (interrupted) {
    std::fprintf(stderr, "raylab: bench interrupted: %zu finished records kept%s%s\n", out.records.size(),
                 o.out.empty() ? "" : " in ", o.out.c_str());
    return kExitInterrupted;
  }
  return 0;
}

}  // namespace

}  // namespace raylab::cli
