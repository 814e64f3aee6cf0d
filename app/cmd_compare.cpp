// `raylab compare A.json B.json`: bench reports cell by cell (bench/compare.h).
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <memory>

#include <fmt/format.h>

#include "base/atomic_file.h"
#include "app/commands.h"
#include "bench/compare.h"

namespace raylab::cli {

namespace {
nlohmann::json read_report(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot open", path));
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::runtime_error(fmt::format("{}: not JSON ({})", path, e.what()));
  }
}
}  // namespace

Runner add_compare(CLI::App& app) {
  struct Opts {
    std::string a, b, out, colour = "auto";
    double fail_above = -1, alpha = 0.05, min_effect = 3.0;
    bool raw = false, no_noise_floor = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "compare two bench reports cell by cell: change in Mrays/s and in the ratio to Embree, build ms "
                 "and bytes; a change is reported when a Mann-Whitney U test over the per-repeat times finds it and it "
                 "is at least the minimum effect");
  cmd->add_option("A", o->a, "the baseline bench report (raylab bench -o)")->required();
  cmd->add_option("B", o->b, "the report to compare with it")->required();
  cmd->add_option("--fail-above", o->fail_above,
                  "exit 1 when a cell is significantly slower than A by more than PCT percent (for CI)")
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--alpha", o->alpha, "significance level of the test")->capture_default_str()->check(CLI::Range(1e-6, 0.5));
  cmd->add_option("--min-effect", o->min_effect,
                  "minimum effect: speed changes under PCT percent are never reported, whatever the test says")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
  add_renamed_option(cmd, "--min-change", "--min-effect PCT");
  cmd->add_flag("--no-noise-floor", o->no_noise_floor,
                "do not raise the minimum effect to the noise floor the two runs measured (the spread of Embree's own "
                "speed within each run)");
  cmd->add_flag("--raw", o->raw,
               "test raw trace times (Mrays/s) instead of times divided by Embree's, timed in alternation with them "
               "(which cancels drift of the machine)");
  cmd->add_option("-o,--out", o->out, "the comparison as JSON ('-' for stdout instead of the table)");
  add_renamed_option(cmd, "--json", "-o/--out FILE");
  cmd->add_option("--colour,--color", o->colour, "auto (when stdout is a terminal), always or never")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "always", "never"}));

  return [o]() {
    if (!o->out.empty() && o->out != "-") check_output_path(o->out);
    const auto a = read_report(o->a), b = read_report(o->b);
    CompareOptions co;
    co.alpha = o->alpha;
    co.min_effect_pct = o->min_effect;
    co.fail_above_pct = o->fail_above;
    co.normalize_by_embree = !o->raw;
    co.noise_floor = !o->no_noise_floor;
    const CompareResult r = compare_bench_reports(a, b, co);
    if (r.cells.empty())
      throw std::runtime_error(fmt::format("{} and {} have no cell (scene, accel, ray set, threads) in common", o->a, o->b));
    const nlohmann::json j = compare_result_json(r, co);
    if (o->out == "-") {
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      const bool colour = o->colour == "always" || (o->colour == "auto" && ::isatty(::fileno(stdout)));
      std::printf("compare %s (A) -> %s (B)\n%s", o->a.c_str(), o->b.c_str(), format_compare_table(r, co, colour).c_str());
      if (!o->out.empty()) write_file_atomically(o->out, j.dump(2) + "\n");
    }
    return r.regressions > 0 ? kExitCheckFailed : 0;
  };
}

}  // namespace raylab::cli
