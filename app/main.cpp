// raylab: render, verify and time ray-tracing acceleration structures.
#include <cstdio>
#include <exception>
#include <map>
#include <stdexcept>

#include <fmt/format.h>

#include "accel/core/simd/instruction_sets.h"
#include "base/spec.h"
#include "app/commands.h"

// The first of the program's initialisers (priority 101 runs before the
// others): a binary compiled for instruction sets this CPU lacks stops here
// with one line, before any code compiled for them runs.
[[gnu::constructor(101)]] static void check_instruction_sets() {
  raylab::exit_unless_cpu_runs_this_binary("raylab");
}

int main(int argc, char** argv) {
  using namespace raylab::cli;
  CLI::App app{"raylab: a testbed for ray-tracing acceleration structures (Embree as the reference)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("raylab 0.1"));
  std::map<CLI::App*, Runner> runners;
  auto add = [&](Runner (*f)(CLI::App&), const char* name) {
    Runner r = f(app);
    runners[app.get_subcommand(name)] = std::move(r);
  };
  add(add_render, "render");
  add(add_verify, "verify");
  add(add_stress, "stress");
  add(add_bench, "bench");
  add(add_rays, "rays");
  add(add_info, "info");
  add(add_scenes, "scenes");
  add(add_accels, "accels");
  add(add_compare, "compare");
  add(add_show, "show");
  add(add_report, "report");
  add(add_memory, "memory");

  std::string names;
  bool known = false;
  for (const auto& [sub, run] : runners) {
    names += (names.empty() ? "" : ", ") + sub->get_name();
    known |= argc > 1 && sub->get_name() == argv[1];
  }
  if (argc > 1 && argv[1][0] != '-' && !known) {
    std::fprintf(stderr, "raylab: error: unknown command '%s' (commands: %s)\n", argv[1], names.c_str());
    return kExitBadInput;
  }
  // Errors name the subcommand and point to its own help, where the options are.
  const std::string command = known ? std::string(argv[1]) : std::string();
  const std::string prefix = command.empty() ? "raylab" : "raylab " + command;
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "%s: error: %s (see %s --help)\n", prefix.c_str(), e.what(), prefix.c_str());
    return kExitBadInput;
  }

  try {
    for (auto& [sub, run] : runners)
      if (sub->parsed()) return run();
  } catch (const std::invalid_argument& e) {  // an option's value: its help says what is accepted
    std::fprintf(stderr, "%s: error: %s (see %s --help)\n", prefix.c_str(), e.what(), prefix.c_str());
    return kExitBadInput;
  } catch (const raylab::SpecError& e) {
    std::fprintf(stderr, "%s: error: %s (see %s --help)\n", prefix.c_str(), e.what(), prefix.c_str());
    return kExitBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: error: %s\n", prefix.c_str(), e.what());
    return kExitBadInput;
  }
  return kExitBadInput;
}
