#include "accel/core/grid/grid_resolution.h"

#include <algorithm>
#include <charconv>
#include <cmath>

#include <fmt/format.h>

#include "base/spec.h"

namespace raylab {

GridRes resolution_by_density(const Vec3d& extent, double count, double lambda) {
  const double target = std::max(1.0, lambda * count);
  bool active[3];
  for (int a = 0; a < 3; ++a) active[a] = extent[a] > 0.0 && std::isfinite(extent[a]);
  double side = 0.0;
  // Drop sides shorter than a cell until the set is stable (at most 3 rounds).
  for (int round = 0; round < 3; ++round) {
    int m = 0;
    double log_volume = 0.0;  // in logs: products of extreme sides stay finite
    for (int a = 0; a < 3; ++a)
      if (active[a]) {
        ++m;
        log_volume += std::log(extent[a]);
      }
    if (m == 0) return {1, 1, 1};
    side = std::exp((log_volume - std::log(target)) / m);
    bool dropped = false;
    for (int a = 0; a < 3; ++a)
      if (active[a] && extent[a] < side) {
        active[a] = false;
        dropped = true;
      }
    if (!dropped) break;
  }
  GridRes r{1, 1, 1};
  for (int a = 0; a < 3; ++a) {
    if (!active[a] || !(side > 0.0)) continue;
    const double k = std::round(extent[a] / side);
    r[a] = static_cast<int32_t>(std::clamp(k, 1.0, static_cast<double>(kMaxGridAxisCells)));
  }
  return r;
}

ChosenResolution choose_resolution(const Vec3d& extent, double count, double lambda, uint64_t max_cells) {
  max_cells = std::max<uint64_t>(1, max_cells);
  ChosenResolution c;
  c.lambda = lambda;
  c.res = resolution_by_density(extent, count, lambda);
  // Each round scales lambda by the overshoot (cells grow about linearly in
  // lambda), with a margin for rounding; the loop ends because lambda falls
  // geometrically and lambda -> 0 gives a single cell.
  for (int guard = 0; guard < 200 && total_cells(c.res) > max_cells; ++guard) {
    const double over = static_cast<double>(total_cells(c.res)) / static_cast<double>(max_cells);
    c.lambda *= std::min(0.95, 0.98 / over);
    c.res = resolution_by_density(extent, count, c.lambda);
    c.capped = true;
  }
  if (total_cells(c.res) > max_cells) c.res = {1, 1, 1};
  return c;
}

ChosenResolution cap_resolution(const GridRes& requested, uint64_t max_cells) {
  max_cells = std::max<uint64_t>(1, max_cells);
  ChosenResolution c;
  c.res = requested;
  c.lambda = 0.0;
  for (int guard = 0; guard < 200 && total_cells(c.res) > max_cells; ++guard) {
    const double scale = std::min(0.97, std::cbrt(static_cast<double>(max_cells) / static_cast<double>(total_cells(c.res))));
    for (auto& k : c.res) k = std::max<int32_t>(1, static_cast<int32_t>(std::floor(k * scale)));
    c.capped = true;
  }
  return c;
}

GridRes parse_grid_resolution(const std::string& text) {
  GridRes r{};
  const char* p = text.data();
  const char* end = text.data() + text.size();
  for (int a = 0; a < 3; ++a) {
    if (a > 0) {
      if (p == end || (*p != 'x' && *p != 'X'))
        throw SpecError(fmt::format("grid resolution '{}' must look like 64x64x32", text));
      ++p;
    }
    int64_t v = 0;
    const auto [next, ec] = std::from_chars(p, end, v);
    if (ec != std::errc() || next == p)
      throw SpecError(fmt::format("grid resolution '{}' must look like 64x64x32", text));
    if (v < 1 || v > kMaxGridAxisCells)
      throw SpecError(fmt::format("grid resolution '{}': each count must be in 1..{}", text, kMaxGridAxisCells));
    r[a] = static_cast<int32_t>(v);
    p = next;
  }
  if (p != end) throw SpecError(fmt::format("grid resolution '{}' must look like 64x64x32", text));
  return r;
}

std::string format_grid_resolution(const GridRes& r) { return fmt::format("{}x{}x{}", r[0], r[1], r[2]); }

}  // namespace raylab
