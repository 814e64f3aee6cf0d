#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include <fmt/format.h>

#include "app/commands.h"
#include "tracer/trace.h"

namespace raylab::cli {

namespace {
bool parse_positive(const std::string& s, int& v) {
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && p == s.data() + s.size() && v > 0;
}
}  // namespace

std::pair<int, int> parse_size(const std::string& text) {
  const auto x = text.find('x');
  int w = 0, h = 0;
  if (x == std::string::npos || !parse_positive(text.substr(0, x), w) || !parse_positive(text.substr(x + 1), h))
    throw std::invalid_argument(fmt::format("invalid size '{}' (expected WIDTHxHEIGHT, e.g. 512x512)", text));
  if (w > kMaxImageSide || h > kMaxImageSide)
    throw std::invalid_argument(
        fmt::format("size '{}' is too large: width and height are at most {}", text, kMaxImageSide));
  return {w, h};
}

std::vector<std::string> parse_name_list(const std::string& text) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= text.size()) {
    const auto comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (!item.empty()) out.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

std::vector<int> parse_int_list(const std::string& text, const char* what) {
  std::vector<int> out;
  for (const auto& item : parse_name_list(text)) {
    int v = 0;
    if (!parse_positive(item, v)) throw std::invalid_argument(fmt::format("invalid {} '{}' (expected positive integers)", what, item));
    out.push_back(v);
  }
  if (out.empty()) throw std::invalid_argument(fmt::format("no {} given", what));
  return out;
}


std::string pick_scene(const std::string& command, const std::string& option, const std::string& positional,
                       const std::string& fallback) {
  if (!option.empty() && !positional.empty())
    throw std::invalid_argument(fmt::format(
        "{} takes one scene, given either positionally or with --scene, not both (got '{}' and '{}')", command,
        positional, option));
  if (!positional.empty()) return positional;
  return option.empty() ? fallback : option;
}

std::string ray_set_size_note(const std::string& set, size_t asked, size_t got) {
  if (got == asked) return {};
  const bool secondary = set == "diffuse" || set == "shadow";
  return fmt::format("note: ray set '{}' holds {} rays, not {}{}\n", set, got, asked,
                     secondary ? " (its rays start from primary hits; primary rays that miss give none)" : "");
}

void check_output_path(const std::string& path, const std::string& option) {
  namespace fs = std::filesystem;
  if (path.empty()) throw std::invalid_argument(fmt::format("{}: empty file name", option));
  std::error_code ec;
  if (fs::is_directory(path, ec))
    throw std::invalid_argument(fmt::format("{} {}: is a directory (give a file name)", option, path));
  const fs::path parent = fs::path(path).parent_path();
  if (!parent.empty() && !fs::is_directory(parent, ec))
    throw std::invalid_argument(fmt::format("{} {}: directory {} does not exist (create it first)", option, path,
                                            parent.string()));
}

CLI::Option* add_accel_list_option(CLI::App* cmd, std::string& accel) {
  return cmd->add_option("--accel", accel,
                         "accelerator specs separated by ';' (',' also works between specs without parameters), or "
                         "'all' (see raylab accels)")
      ->capture_default_str();
}

void add_renamed_option(CLI::App* cmd, const std::string& old_name, const std::string& new_name) {
  cmd->add_option_function<std::string>(old_name,
                                        [old_name, new_name](const std::string&) {
                                          throw CLI::ValidationError(
                                              fmt::format("{} was renamed: use {}", old_name, new_name));
                                        })
      ->group("");  // not in --help: it exists only to say where the option went
}

void add_scene_options(CLI::App* cmd, std::string& positional, std::string& option, const std::string& help) {
  cmd->add_option("scene", positional, help);
  cmd->add_option("--scene", option, "the scene, as the positional argument");
}

CLI::Option* add_threads_option(CLI::App* cmd, int& threads) {
  return cmd->add_option("-t,--threads", threads, "worker threads (0 = all cores)")
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            int n = 0;
            const auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
            if (ec != std::errc() || p != v.data() + v.size() || n < 0 || n > 4096)
              return fmt::format("takes one thread count from 0 (all cores) to 4096, not '{}'", v);
            return {};
          },
          "COUNT"));
}

CLI::Option* add_ray_count_option(CLI::App* cmd, size_t& rays, const std::string& help,
                                  const std::string& names) {
  return cmd->add_option(names, rays, help)
      ->capture_default_str()
      ->check(CLI::Validator(
          [](std::string& v) -> std::string {
            size_t n = 0;
            const auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
            if (ec == std::errc() && p == v.data() + v.size() && n >= 1 && n <= (size_t{1} << 28)) return {};
            if (!v.empty() && std::isalpha(static_cast<unsigned char>(v[0])))
              return fmt::format("takes a ray count (e.g. --rays 65536); to choose ray sets such as '{}' use "
                                 "--ray-sets NAMES",
                                 v);
            return fmt::format("takes a ray count from 1 to 268435456, not '{}'", v);
          },
          "N"));
}

std::vector<int> parse_thread_list(const std::string& text) {
  std::vector<int> out;
  for (const auto& item : parse_name_list(text)) {
    int v = -1;
    const auto [p, ec] = std::from_chars(item.data(), item.data() + item.size(), v);
    if (ec != std::errc() || p != item.data() + item.size() || v < 0 || v > 4096)
      throw std::invalid_argument(
          fmt::format("invalid thread count '{}' (expected counts from 0 = all cores to 4096, comma separated)", item));
    if (v == 0) v = hardware_threads();
    if (std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
  }
  if (out.empty()) throw std::invalid_argument("no thread count given");
  return out;
}

std::string lower_extension_of(const std::string& path) {
  const auto dot = path.rfind('.');
  const auto slash = path.rfind('/');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

bool stderr_is_terminal() { return ::isatty(::fileno(stderr)) != 0; }

std::string format_duration(double s) {
  if (!(s >= 0) || s > 1e7) return "?";
  if (s < 60) return fmt::format("{:.0f} s", std::ceil(s));
  if (s < 3600) return fmt::format("{} min {:02} s", static_cast<int>(s / 60), static_cast<int>(s) % 60);
  return fmt::format("{} h {:02} min", static_cast<int>(s / 3600), static_cast<int>(s / 60) % 60);
}

}  // namespace raylab::cli
