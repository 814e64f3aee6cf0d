#pragma once
// `raylab render --aov nodes|tris|time`: per-pixel cost pictures, the
// standard figure of acceleration-structure papers. For each pixel's
// primary ray: nodes/cells visited, triangle tests (the instrumented
// kernels' per-ray counters) or trace time (min over repeats, in ns).
// One structure: a PNG with colour bar and legend, plus the raw values as
// PFM. Several (a list or `all`): a contact sheet with one shared scale.
#include <string>
#include <vector>

#include "scenes/scene.h"

namespace raylab::cli {

struct AovOptions {
  std::string kind;  // nodes, tris or time
  std::vector<std::string> accels;
  std::string out;   // .png (picture + raw .pfm next to it) or .pfm (raw values only)
  int width = 0, height = 0;
  int time_repeats = 5;
};

// Throws std::invalid_argument for an unknown kind.
void check_aov_kind(const std::string& kind);

// Runs the AOV render for an already loaded scene; prints one line per
// structure. Returns the process exit code.
int render_cost_aov(const Scene& scene, const AovOptions& options);

}  // namespace raylab::cli
