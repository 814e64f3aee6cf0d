#include "accel/grid/hash_grid.h"

#include <algorithm>
#include <atomic>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_scan.h>
#include <tbb/parallel_sort.h>

#include "accel/grid/cell_overlap.h"
#include "accel/grid/grid_build_start.h"
#include "accel/grid/grid_stats.h"

namespace raylab {

namespace {

constexpr size_t kTriangleGrain = 256;

struct KeyRef {
  uint64_t key;
  uint32_t id;
  bool operator<(const KeyRef& o) const { return key != o.key ? key < o.key : id < o.id; }
};

// Pass 1 and 2: per-triangle cell counts, then their exclusive prefix sum
// (first[i] = first pair of triangle i; first[n] = total). Returns false as
// soon as the total exceeds `limit` (the threads stop counting).
bool count_pairs(const DdaGrid& g, AssignMode mode, std::span<const LeafTriangle> tris, uint64_t limit,
                 std::vector<uint64_t>& first) {
  const size_t n = tris.size();
  first.assign(n + 1, 0);
  std::atomic<uint64_t> total{0};
  std::atomic<bool> over{false};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kTriangleGrain), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end() && !over.load(std::memory_order_relaxed); ++i) {
      uint64_t c = 0, published = 0;
      for_each_assigned_cell(g, mode, tris[i].p0, tris[i].p1, tris[i].p2, [&](int32_t, int32_t, int32_t) {
        if ((++c & 4095) != 0) return true;
        if (total.fetch_add(c - published) + (c - published) > limit) over = true;
        published = c;
        return !over.load(std::memory_order_relaxed);
      });
      first[i] = c;
      if (total.fetch_add(c - published) + (c - published) > limit) over = true;
    }
  });
  if (over) return false;
  const uint64_t sum = tbb::parallel_scan(
      tbb::blocked_range<size_t>(0, n, 1 << 14), uint64_t{0},
      [&](const tbb::blocked_range<size_t>& r, uint64_t sum, bool is_final) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
          const uint64_t c = first[i];
          if (is_final) first[i] = sum;
          sum += c;
        }
        return sum;
      },
      [](uint64_t a, uint64_t b) { return a + b; });
  first[n] = sum;
  return true;
}

}  // namespace

HashGrid build_hash_grid(const TriangleMesh& mesh, const GridOptions& opt, BuildStats& stats) {
  HashGrid g;
  GridBuildStart start;
  if (!start_grid_build(mesh, opt, g.tris, g.empty, start)) return g;
  const size_t n = start.triangles;
  const Vec3d &lo = start.lo, &hi = start.hi;
  // Empty cells cost no memory, but walking and assigning them costs time:
  // the cells are capped at 8 per byte of budget (2^33 for the default
  // 1 GiB), far above any density the rule asks for in practice.
  const uint64_t budget = start.budget;
  const uint64_t max_cells = std::max<uint64_t>(1, budget * 8);
  ChosenResolution chosen = start.first_resolution(opt, max_cells);
  // The build's peak: the (key, id) pairs, the references and the table
  // (32 bytes per occupied cell) must fit the budget.
  const uint64_t max_refs = std::min<uint64_t>(budget / (sizeof(KeyRef) + sizeof(uint32_t)), UINT32_MAX);

  std::vector<uint64_t> first;
  std::vector<KeyRef> pairs;
  size_t occupied = 0;
  while (true) {
    g.dda = make_dda_grid(lo, hi, chosen.res);
    if (count_pairs(g.dda, opt.assign, g.tris, max_refs, first)) {
      // Pass 3: fill the (key, id) pairs, then sort them by cell.
      pairs.resize(first[n]);
      const DdaGrid& dda = g.dda;
      tbb::parallel_for(tbb::blocked_range<size_t>(0, n, kTriangleGrain), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
          uint64_t slot = first[i];
          for_each_assigned_cell(dda, opt.assign, g.tris[i].p0, g.tris[i].p1, g.tris[i].p2,
                                 [&](int32_t x, int32_t y, int32_t z) {
                                   pairs[slot++] =
                                       KeyRef{static_cast<uint64_t>(dda.index(x, y, z)), static_cast<uint32_t>(i)};
                                 });
        }
      });
      tbb::parallel_sort(pairs.begin(), pairs.end());
      // Runs of equal keys -> occupied cells.
      occupied = 0;
      for (size_t i = 0; i < pairs.size(); ++i) occupied += (i == 0 || pairs[i].key != pairs[i - 1].key);
      const uint64_t peak = pairs.size() * (sizeof(KeyRef) + sizeof(uint32_t)) + 2 * occupied * sizeof(CellSlot);
      if (peak <= budget) break;
    }
    std::vector<KeyRef>().swap(pairs);
    if (total_cells(chosen.res) == 1)
      throw std::runtime_error(fmt::format(
          "hashgrid: a memory budget of {} MiB cannot hold the references of {} triangles", opt.budget_mib, n));
    const ChosenResolution smaller = start.smaller_resolution(opt, chosen, max_cells);
    chosen.res = smaller.res;
    chosen.lambda = smaller.lambda;
    chosen.capped = true;
  }
  std::vector<uint64_t>().swap(first);
  if (chosen.capped) {
    const std::string requested = opt.res ? "res=" + format_grid_resolution(*opt.res) : fmt::format("density={}", opt.density);
    const std::string used = opt.res ? "res=" + format_grid_resolution(chosen.res)
                                     : fmt::format("density={:.4g} (res={})", chosen.lambda, format_grid_resolution(chosen.res));
    warn_budget_capped("hashgrid", requested, used, opt.budget_mib);
  }

  const uint64_t total = pairs.size();
  g.table = CellHashTable(occupied);
  g.refs.resize(total);
  uint64_t probe_sum = 0;
  uint32_t probe_max = 0, max_per_cell = 0;
  for (size_t i = 0; i < pairs.size();) {
    size_t j = i;
    while (j < pairs.size() && pairs[j].key == pairs[i].key) {
      g.refs[j] = pairs[j].id;
      ++j;
    }
    const uint32_t count = static_cast<uint32_t>(j - i);
    const uint32_t probes = g.table.insert(pairs[i].key, static_cast<uint32_t>(i), count);
    probe_sum += probes;
    probe_max = std::max(probe_max, probes);
    max_per_cell = std::max(max_per_cell, count);
    i = j;
  }

  add_occupancy_stats(stats, total_cells(chosen.res), occupied, total, max_per_cell, n);
  add_resolution_stats(stats, chosen.res, opt.res ? 0.0 : chosen.lambda, opt.res ? 0.0 : opt.density);
  stats.extra["budget_capped"] = chosen.capped ? 1.0 : 0.0;
  stats.extra["hash_capacity"] = static_cast<double>(g.table.capacity());
  stats.extra["hash_load"] = static_cast<double>(occupied) / static_cast<double>(g.table.capacity());
  stats.extra["hash_mean_probes"] = occupied ? static_cast<double>(probe_sum) / static_cast<double>(occupied) : 0.0;
  stats.extra["hash_max_probes"] = probe_max;
  stats.max_depth = 1;
  stats.avg_depth = 1.0;
  stats.bytes = g.table.bytes() + g.refs.capacity() * sizeof(uint32_t) + g.tris.capacity() * sizeof(LeafTriangle) +
                sizeof(HashGrid);
  return g;
}

}  // namespace raylab
