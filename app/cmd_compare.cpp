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
    std::string a, b, json, colour = "auto";
    double fail_above = -1, alpha = 0.05, min_change = 5.0;
    bool raw = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "compare two bench reports cell by cell: change in Mrays/s, build ms and bytes, with a "
                 "Mann-Whitney U test over the per-repeat times");
  cmd->add_option("A", o->a, "the baseline bench report (raylab bench --json)")->required();
  cmd->add_option("B", o->b, "the report to compare with it")->required();
  cmd->add_option("--fail-above", o->fail_above,
                  "exit 1 when a cell is significantly slower than A by more than PCT percent (for CI)")
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--alpha", o->alpha, "significance level of the test")->capture_default_str()->check(CLI::Range(1e-6, 0.5));
  cmd->add_option("--min-change", o->min_change, "noise floor: speed changes under PCT percent are never significant")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_flag("--raw", o->raw,
               "test raw trace times instead of times divided by the same cell's Embree time (which cancels "
               "machine-wide drift between the two runs)");
  cmd->add_option("-o,--json", o->json, "write the comparison as JSON to this file ('-' for stdout, no table)");
  cmd->add_option("--colour,--color", o->colour, "auto (when stdout is a terminal), always or never")
      ->capture_default_str()
      ->check(CLI::IsMember({"auto", "always", "never"}));

  return [o]() {
    const auto a = read_report(o->a), b = read_report(o->b);
    CompareOptions co;
    co.alpha = o->alpha;
    co.min_change_pct = o->min_change;
    co.fail_above_pct = o->fail_above;
    co.normalize_by_embree = !o->raw;
    const CompareResult r = compare_bench_reports(a, b, co);
    if (r.cells.empty())
      throw std::runtime_error(fmt::format("{} and {} have no cell (scene, accel, ray set, threads) in common", o->a, o->b));
    const nlohmann::json j = compare_result_json(r, co);
    if (o->json == "-") {
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      const bool colour = o->colour == "always" || (o->colour == "auto" && ::isatty(::fileno(stdout)));
      std::printf("compare %s (A) -> %s (B)\n%s", o->a.c_str(), o->b.c_str(), format_compare_table(r, co, colour).c_str());
      if (!o->json.empty()) write_file_atomically(o->json, j.dump(2) + "\n");
    }
    return r.regressions > 0 ? kExitCheckFailed : 0;
  };
}

}  // namespace raylab::cli
