#pragma once
// Each subcommand of `raylab` registers its options on the CLI11 app and
// returns the function that runs it (returning the process exit code).
#include <functional>
#include <string>
#include <utility>

#include <CLI/CLI.hpp>

namespace raylab::cli {

// Exit codes: 0 success, 1 a check failed (verify disagreements), 2 bad
// input (arguments, scenes, files) or any other error.
inline constexpr int kExitCheckFailed = 1;
inline constexpr int kExitBadInput = 2;

using Runner = std::function<int()>;

Runner add_render(CLI::App& app);
Runner add_verify(CLI::App& app);
Runner add_stress(CLI::App& app);
Runner add_bench(CLI::App& app);
Runner add_rays(CLI::App& app);
Runner add_info(CLI::App& app);
Runner add_scenes(CLI::App& app);
Runner add_accels(CLI::App& app);

// "512x384" -> (512, 384); throws CLI::ValidationError style std::invalid_argument.
std::pair<int, int> parse_size(const std::string& text);

// Comma-separated list of positive integers ("1,2").
std::vector<int> parse_int_list(const std::string& text, const char* what);
std::vector<std::string> parse_name_list(const std::string& text);

}  // namespace raylab::cli
