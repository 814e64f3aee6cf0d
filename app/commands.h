#pragma once
// Each subcommand of `raylab` registers its options on the CLI11 app and
// returns the function that runs it (returning the process exit code).
#include <functional>
#include <string>
#include <utility>

#include <CLI/CLI.hpp>

namespace raylab::cli {

// Exit codes: 0 success, 1 a check failed (verify disagreements, compare
// regressions), 2 bad input (arguments, scenes, files) or any other error,
// 130 interrupted by Ctrl-C (as a shell reports SIGINT).
inline constexpr int kExitCheckFailed = 1;
inline constexpr int kExitBadInput = 2;
inline constexpr int kExitInterrupted = 130;  // Ctrl-C: finished records kept, "complete": false

using Runner = std::function<int()>;

Runner add_render(CLI::App& app);
Runner add_verify(CLI::App& app);
Runner add_stress(CLI::App& app);
Runner add_bench(CLI::App& app);
Runner add_rays(CLI::App& app);
Runner add_info(CLI::App& app);
Runner add_scenes(CLI::App& app);
Runner add_accels(CLI::App& app);
Runner add_compare(CLI::App& app);
Runner add_show(CLI::App& app);
Runner add_report(CLI::App& app);
Runner add_memory(CLI::App& app);

// The largest image side --size takes (a 65536 x 65536 image is 48 GiB of floats).
inline constexpr int kMaxImageSide = 65536;

// "512x384" -> (512, 384); throws std::invalid_argument naming the limit.
std::pair<int, int> parse_size(const std::string& text);

// Output files go where they are asked, nowhere else: the directory of
// `path` must exist (a missing one is bad input, exit 2, and nothing is
// created) and `path` must not be a directory. `option` names the option in
// the message. Checked before any long work, so a typo costs nothing.
void check_output_path(const std::string& path, const std::string& option = "-o");

// "--accel" taking a list of specs (verify, stress, bench): one help text.
CLI::Option* add_accel_list_option(CLI::App* cmd, std::string& accel);

// A hidden option under an old name that fails with "OLD was renamed: use
// NEW", so a script written for the old name gets told the new one.
void add_renamed_option(CLI::App* cmd, const std::string& old_name, const std::string& new_name);

// Comma-separated list of positive integers ("1,2").
std::vector<int> parse_int_list(const std::string& text, const char* what);
std::vector<std::string> parse_name_list(const std::string& text);

// --- One vocabulary for every subcommand (README: "Command line") ---
// --ray-sets NAMES  which ray sets;  --rays N  how many rays per set;
// a positional scene or --scene;  -t/--threads (0 = all cores);  -o/--out
// the command's output file (render's image, the JSON report of verify,
// stress, bench and compare, report's page, rays' ray file, show's pictures).

// The scene given positionally or with --scene (both at once is an error
// naming the two); `fallback` when neither.
std::string pick_scene(const std::string& command, const std::string& option, const std::string& positional,
                       const std::string& fallback);

// Adds the positional "scene" (described by `help`) and "--scene", its
// synonym; pick_scene() then chooses.
void add_scene_options(CLI::App* cmd, std::string& positional, std::string& option, const std::string& help);

// Adds "-t,--threads" taking one count; 0 (the default) = all cores.
CLI::Option* add_threads_option(CLI::App* cmd, int& threads);

// Adds "--rays" taking one ray count; a set name given by habit gets a
// message pointing to --ray-sets instead of CLI11's range error.
CLI::Option* add_ray_count_option(CLI::App* cmd, size_t& rays, const std::string& help,
                                  const std::string& names = "--rays");

// Ray sets built from primary hits (diffuse, shadow) hold one ray per hit,
// so fewer than asked when rays miss: the note saying so (empty when the set
// holds what was asked; one line ending in a newline otherwise).
std::string ray_set_size_note(const std::string& set, size_t asked, size_t got);

// "1,0,4" -> thread counts with 0 replaced by all cores (de-duplicated, in order).
std::vector<int> parse_thread_list(const std::string& text);

// Lower-case extension of a file name with the dot (".png"), "" when none.
std::string lower_extension_of(const std::string& path);

// True when stderr is a terminal (progress lines are drawn only then).
bool stderr_is_terminal();

// "12.3 s", "4 min 05 s", "1 h 02 min": for progress estimates.
std::string format_duration(double seconds);

}  // namespace raylab::cli
