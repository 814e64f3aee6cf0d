#include "scenes/nff_view.h"

#include <charconv>
#include <fstream>
#include <sstream>
#include <vector>

#include <fmt/format.h>

#include "scenes/mesh_import.h"

namespace raylab {

namespace {

bool parse_float(const std::string& s, float& v) {
  const auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && p == s.data() + s.size();
}

}  // namespace

std::optional<View> read_nff_view(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw SceneLoadError(fmt::format("{}: cannot open for reading", path));
  View v;
  bool in_view = false, got_from = false, got_at = false, got_up = false, got_angle = false, got_res = false;
  std::string line;
  int line_no = 0;
  // The record comes first in NFF files; stop at the first other entity.
  while (std::getline(in, line) && line_no < 10000) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::vector<std::string> words;
    for (std::string w; ls >> w;) words.push_back(w);
    if (words.empty() || words[0][0] == '#') continue;
    const std::string& key = words[0];
    if (!in_view) {
      if (key != "v") return std::nullopt;  // geometry before any view record
      in_view = true;
      continue;
    }
    auto numbers = [&](size_t n) {
      std::vector<float> out;
      if (words.size() != n + 1)
        throw SceneLoadError(fmt::format("{}: line {}: NFF view record: '{}' needs {} number{}", path, line_no, key, n,
                                         n == 1 ? "" : "s"));
      for (size_t i = 1; i <= n; ++i) {
        float x;
        if (!parse_float(words[i], x))
          throw SceneLoadError(fmt::format("{}: line {}: NFF view record: '{}' is not a number", path, line_no, words[i]));
        out.push_back(x);
      }
      return out;
    };
    if (key == "from") {
      const auto n = numbers(3);
      v.from = Vec3f(n[0], n[1], n[2]);
      got_from = true;
    } else if (key == "at") {
      const auto n = numbers(3);
      v.at = Vec3f(n[0], n[1], n[2]);
      got_at = true;
    } else if (key == "up") {
      const auto n = numbers(3);
      v.up = Vec3f(n[0], n[1], n[2]);
      got_up = true;
    } else if (key == "angle") {
      v.fov_deg = numbers(1)[0];
      got_angle = true;
    } else if (key == "hither") {
      numbers(1);
    } else if (key == "resolution") {
      const auto n = numbers(2);
      if (n[0] != static_cast<float>(static_cast<int>(n[0])) || n[1] != static_cast<float>(static_cast<int>(n[1])))
        throw SceneLoadError(fmt::format("{}: line {}: NFF view record: resolution must be two integers", path, line_no));
      v.width = static_cast<int>(n[0]);
      v.height = static_cast<int>(n[1]);
      got_res = true;
    } else {
      break;  // the record ended
    }
    if (got_from && got_at && got_up && got_angle && got_res) break;
  }
  if (!in_view) return std::nullopt;
  const char* missing = !got_from ? "from" : !got_at ? "at" : !got_up ? "up" : !got_angle ? "angle" : !got_res ? "resolution" : nullptr;
  if (missing) throw SceneLoadError(fmt::format("{}: NFF view record has no '{}' line", path, missing));
  if (const std::string why = view_problem(v); !why.empty())
    throw SceneLoadError(fmt::format("{}: NFF view record: {}", path, why));
  return v;
}

}  // namespace raylab
