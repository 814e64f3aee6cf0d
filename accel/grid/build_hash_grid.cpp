#include "accel/grid/hash_grid.h"

#include <algorithm>
#include <atomic>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_scan.h>
#include <tbb/parallel_sort.h>

#include "accel/grid/cell_blocks.h"
#include "accel/core/grid/cell_overlap.h"
#include "accel/core/grid/exclusive_scan.h"
#include "accel/grid/grid_build_start.h"
#include "accel/core/grid/grid_stats.h"

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
  exclusive_scan_counts(first);
  return true;
}

// The SIMD blocks the cells of pairs sorted by key need (cell_blocks.h).
template <typename KeyOf>
uint64_t blocks_of_key_runs(const std::vector<KeyRef>& pairs, KeyOf key) {
  uint64_t blocks = 0;
  for (size_t i = 0, j = 0; i < pairs.size(); i = j) {
    for (j = i + 1; j < pairs.size() && key(pairs[j]) == key(pairs[i]);) ++j;
    blocks += cell_block_count(static_cast<uint32_t>(j - i));
  }
  return blocks;
}

}  // namespace

HashGrid build_hash_grid(const TriangleMesh& mesh, const GridOptions& opt, BuildStats& stats) {
  HashGrid g;
  GridBuildStart start;
  if (!start_grid_build(mesh, opt, g, start)) return g;
  // Empty cells cost no memory, but walking and assigning them costs time:
  // the cells are capped at 8 per byte of budget (2^33 for the default
  // 1 GiB), far above any density the rule asks for in practice.
  const uint64_t max_cells = std::max<uint64_t>(1, start.budget * 8);
  ChosenResolution chosen = start.first_resolution(opt, max_cells);
  // The build's peak: the (key, id) pairs, the references and the table
  // (32 bytes per occupied cell) must fit the budget.
  // With SIMD blocks, the blocks too (at least 40 bytes per reference).
  const uint64_t max_refs =
      std::min<uint64_t>(start.budget / (sizeof(KeyRef) + sizeof(uint32_t) + (opt.leaf_blocks() ? reference_bytes(true) : 0)),
                         UINT32_MAX);

  const auto key_of = [](const KeyRef& p) { return p.key; };
  std::vector<uint64_t> first;
  std::vector<KeyRef> pairs;
  size_t occupied = 0;
  while (true) {
    g.dda = make_dda_grid(start.lo, start.hi, chosen.res);
    if (count_pairs(g.dda, opt.assign, g.tris, max_refs, first)) {
      // Pass 3: fill the (key, id) pairs, then sort them by cell.
      pairs.resize(first[start.triangles]);
      const DdaGrid& dda = g.dda;
      tbb::parallel_for(tbb::blocked_range<size_t>(0, start.triangles, kTriangleGrain), [&](const tbb::blocked_range<size_t>& r) {
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
      occupied = count_key_runs(pairs, key_of);
      uint64_t peak = pairs.size() * (sizeof(KeyRef) + sizeof(uint32_t)) + 2 * occupied * sizeof(CellSlot);
      if (opt.leaf_blocks()) peak += blocks_of_key_runs(pairs, key_of) * sizeof(CellTriangleBlock);
      if (peak <= start.budget) break;
    }
    std::vector<KeyRef>().swap(pairs);
    start.shrink(opt, chosen, max_cells, "hashgrid", "references");
  }
  std::vector<uint64_t>().swap(first);
  start.warn_if_capped(opt, chosen, "hashgrid");

  const uint64_t total = pairs.size();
  const CellTableFigures table =
      fill_cell_table(pairs, occupied, key_of, [](const KeyRef& p) { return p.id; }, g.table, g.refs);

  add_occupancy_stats(stats, total_cells(chosen.res), occupied, total, table.max_list, start.triangles);
  add_resolution_stats(stats, chosen.res, opt.res ? 0.0 : chosen.lambda, opt.res ? 0.0 : opt.density);
  stats.extra["budget_capped"] = chosen.capped ? 1.0 : 0.0;
  stats.extra["hash_capacity"] = static_cast<double>(g.table.capacity());
  stats.extra["hash_load"] = static_cast<double>(occupied) / static_cast<double>(g.table.capacity());
  stats.extra["hash_mean_probes"] =
      occupied ? static_cast<double>(table.probe_sum) / static_cast<double>(occupied) : 0.0;
  stats.extra["hash_max_probes"] = table.max_probes;
  stats.max_depth = 1;
  stats.avg_depth = 1.0;
  if (opt.leaf_blocks()) {
    std::vector<uint32_t> starts;
    starts.reserve(occupied);
    for (const CellSlot& slot : g.table.slots())
      if (slot.key != CellHashTable::kEmptyKey) starts.push_back(slot.begin);
    CellBlocks cb = to_cell_blocks(mesh, g.refs, starts);
    g.table.remap_runs([&](uint32_t& begin, uint32_t& count) {
      const uint32_t first = cb.block_at[begin];
      count = cb.block_at[begin + count] - first;
      begin = first;
    });
    g.blocks = std::move(cb.blocks);
    std::vector<uint32_t>().swap(g.refs);
    std::vector<LeafTriangle>().swap(g.tris);
  }
  stats.extra["cell_blocks"] = static_cast<double>(g.blocks.size());
  stats.bytes = g.table.bytes() + g.refs.capacity() * sizeof(uint32_t) + g.tris.capacity() * sizeof(LeafTriangle) +
                g.blocks.capacity() * sizeof(CellTriangleBlock) + sizeof(HashGrid);
  return g;
}

}  // namespace raylab
