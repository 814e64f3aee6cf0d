#include "accel/core/grid/cell_lists.h"

#include "accel/core/grid/exclusive_scan.h"

#include <algorithm>
#include <atomic>
#include <numeric>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_scan.h>

namespace raylab {

namespace {

constexpr size_t kTriangleGrain = 256;
constexpr size_t kCellGrain = 1 << 14;

}  // namespace

bool build_cell_lists(const DdaGrid& g, AssignMode mode, std::span<const LeafTriangle> tris,
                      std::span<const uint32_t> ids, uint64_t max_refs, CellLists& out) {
  out = CellLists{};
  const size_t cells = g.cells();
  std::vector<uint32_t> counts(cells + 1, 0);

  // Pass 1: count (per cell, and in total to check the budget before
  // filling). Threads publish their counts in chunks and all stop once the
  // total exceeds the limit, so an oversized request costs little time.
  const uint64_t limit = std::min<uint64_t>(max_refs, UINT32_MAX);
  constexpr uint64_t kPublish = 4096;
  std::atomic<uint64_t> total{0};
  std::atomic<bool> over{false};
  tbb::parallel_for(tbb::blocked_range<size_t>(0, ids.size(), kTriangleGrain), [&](const tbb::blocked_range<size_t>& r) {
    uint64_t local = 0;
    for (size_t i = r.begin(); i < r.end() && !over.load(std::memory_order_relaxed); ++i) {
      const LeafTriangle& t = tris[ids[i]];
      for_each_assigned_cell(g, mode, t.p0, t.p1, t.p2, [&](int32_t x, int32_t y, int32_t z) {
        std::atomic_ref<uint32_t>(counts[g.index(x, y, z)]).fetch_add(1, std::memory_order_relaxed);
        if (++local < kPublish) return true;
        if (total.fetch_add(local) + local > limit) over = true;
        local = 0;
        return !over.load(std::memory_order_relaxed);
      });
    }
    if (total.fetch_add(local) + local > limit) over = true;
  });
  if (over) return false;

  // Pass 2: offsets.
  exclusive_scan_counts(counts, kCellGrain);
  out.offsets = std::move(counts);

  // Pass 3: fill through per-cell cursors.
  out.refs.resize(out.offsets.back());
  std::vector<uint32_t> cursor(out.offsets.begin(), out.offsets.end() - 1);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, ids.size(), kTriangleGrain), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const uint32_t id = ids[i];
      const LeafTriangle& t = tris[id];
      for_each_assigned_cell(g, mode, t.p0, t.p1, t.p2, [&](int32_t x, int32_t y, int32_t z) {
        const uint32_t slot =
            std::atomic_ref<uint32_t>(cursor[g.index(x, y, z)]).fetch_add(1, std::memory_order_relaxed);
        out.refs[slot] = id;
      });
    }
  });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, cells, kCellGrain), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t c = r.begin(); c < r.end(); ++c) {
      const uint32_t b = out.offsets[c], e = out.offsets[c + 1];
      if (e - b > 1) std::sort(out.refs.begin() + b, out.refs.begin() + e);
    }
  });
  return true;
}

CellOccupancy measure_occupancy(std::span<const uint32_t> offsets) {
  CellOccupancy o;
  if (offsets.empty()) return o;
  o.cells = offsets.size() - 1;
  o.refs = offsets.back() - offsets.front();
  for (size_t c = 0; c + 1 < offsets.size(); ++c) {
    const uint32_t n = offsets[c + 1] - offsets[c];
    o.nonempty += n != 0;
    o.max_per_cell = std::max(o.max_per_cell, n);
  }
  return o;
}

}  // namespace raylab
