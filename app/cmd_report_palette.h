#pragma once
// One colour per structure, the same in every chart of `raylab report`, in
// bench/plot.py (which reads it from `raylab accels --json`) and in the
// README. Known names have fixed colours (chosen for mutual contrast from
// the Tableau-10 / Okabe-Ito families); a name not listed gets one of the
// spare colours by a hash of the name, so it is stable too. Variants of a
// structure (a spec with parameters) take the base colour, lightened.
#include <array>
#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>

namespace raylab::cli {

inline std::string structure_colour_of_name(const std::string& name) {
  static const std::pair<const char*, const char*> fixed[] = {
      {"embree", "#1f1f1f"},   {"brute", "#8c8c8c"},    {"bvh", "#1f77b4"},     {"kdtree", "#d62728"},
      {"grid", "#2ca02c"},     {"hashgrid", "#98df8a"}, {"grid2", "#006d2c"},   {"octree", "#9467bd"},
      {"loose_octree", "#c5b0d5"}, {"hgrid", "#17becf"}, {"bsp", "#ff7f0e"},    {"hybrid", "#e377c2"},
      {"irgrid", "#bcbd22"},
  };
  for (const auto& [n, c] : fixed)
    if (name == n) return c;
  static const std::array<const char*, 6> spare = {"#8c564b", "#7f7f00", "#ff9896", "#aec7e8", "#c49c94", "#dbdb8d"};
  uint32_t h = 2166136261u;  // FNV-1a
  for (unsigned char ch : name) h = (h ^ ch) * 16777619u;
  return spare[h % spare.size()];
}

// "#rrggbb" mixed with white by `amount` in [0, 1].
inline std::string lighten_colour(const std::string& hex, double amount) {
  auto chan = [&](int i) { return std::stoi(hex.substr(1 + 2 * i, 2), nullptr, 16); };
  char buf[8];
  int c[3];
  for (int i = 0; i < 3; ++i) c[i] = static_cast<int>(chan(i) + (255 - chan(i)) * amount + 0.5);
  std::snprintf(buf, sizeof buf, "#%02x%02x%02x", c[0], c[1], c[2]);
  return buf;
}

// The colour of a full spec: its structure's colour, lightened for a variant.
inline std::string structure_colour(const std::string& spec) {
  const auto colon = spec.find(':');
  const std::string base = structure_colour_of_name(spec.substr(0, colon));
  return colon == std::string::npos ? base : lighten_colour(base, 0.45);
}

}  // namespace raylab::cli
