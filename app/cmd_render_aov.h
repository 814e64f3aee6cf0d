#pragma once
// `raylab render --aov nodes|tris|time`: per-pixel cost pictures, the
// standard figure of acceleration-structure papers. For each pixel's
// primary ray: nodes/cells visited, triangle tests (the instrumented
// kernels' per-ray counters) or trace time (min over repeats, in ns).
// One structure: a PNG with colour bar and legend, plus the raw values as
// PFM. Several (a list or `all`): a contact sheet, on one shared log scale by
// default (a linear shared scale lets one costly structure saturate the
// others' tiles), or as --aov-scale says.
#include <atomic>
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
  // Colour scale (--aov-scale): "auto" (a sheet: one log scale for all tiles;
  // one picture: linear unless its values span orders of magnitude), "log"
  // or "linear" (one scale for all tiles), "each" (each tile its own linear
  // scale and colour bar).
  std::string scale = "auto";
  // Ctrl-C: polled per block of pixels; once set nothing is written and
  // render_cost_aov returns kExitInterrupted.
  const std::atomic<bool>* stop = nullptr;
};

// Throws std::invalid_argument for an unknown kind or scale.
void check_aov_kind(const std::string& kind);
void check_aov_scale(const std::string& scale);

// Runs the AOV render for an already loaded scene; prints one line per
// structure. Returns the process exit code.
int render_cost_aov(const Scene& scene, const AovOptions& options);

}  // namespace raylab::cli
