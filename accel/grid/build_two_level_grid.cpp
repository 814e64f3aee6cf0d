#include "accel/grid/two_level_grid.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "accel/grid/cell_lists.h"
#include "accel/grid/grid_stats.h"

namespace raylab {

namespace {

struct SubGridPlan {
  uint32_t top_cell = 0;
  Vec3d lo = Vec3d::Zero(), hi = Vec3d::Zero();  // padded box of the sub-grid
  Vec3d extent = Vec3d::Zero();                  // unpadded extent, for the resolution rule
  GridRes res{1, 1, 1};
};

// The part of top cell `cell` that holds its triangles: their bounds
// clipped to the cell (enlarged by the top grid's assignment margin, as the
// assignment was), then padded like a grid box.
SubGridPlan plan_subgrid(const DdaGrid& top, uint32_t cell, std::span<const uint32_t> ids,
                         std::span<const GridTriangle> tris) {
  SubGridPlan p;
  p.top_cell = cell;
  const int64_t c[3] = {cell % top.res[0], (cell / top.res[0]) % top.res[1], cell / (static_cast<int64_t>(top.res[0]) * top.res[1])};
  Vec3d blo = Vec3d::Constant(std::numeric_limits<double>::infinity());
  Vec3d bhi = -blo;
  for (const uint32_t id : ids) {
    for (const Vec3f* v : {&tris[id].p0, &tris[id].p1, &tris[id].p2}) {
      blo = blo.cwiseMin(v->cast<double>());
      bhi = bhi.cwiseMax(v->cast<double>());
    }
  }
  for (int a = 0; a < 3; ++a) {
    blo[a] = std::max(blo[a], top.boundary(a, c[a]) - top.margin[a]);
    bhi[a] = std::min(bhi[a], top.boundary(a, c[a] + 1) + top.margin[a]);
    if (bhi[a] < blo[a]) bhi[a] = blo[a];  // only possible through rounding
  }
  p.extent = bhi - blo;
  double magnitude = 0.0;
  for (int a = 0; a < 3; ++a) magnitude = std::max({magnitude, std::fabs(blo[a]), std::fabs(bhi[a])});
  const double largest_top_cell = std::max({top.cell[0], top.cell[1], top.cell[2]});
  const double pad = std::max({1e-5 * p.extent.maxCoeff(), 1e-7 * largest_top_cell, 1e-6 * magnitude, 1e-30});
  p.lo = blo.array() - pad;
  p.hi = bhi.array() + pad;
  return p;
}

struct Attempt {
  bool ok = false;
  uint64_t sub_cells = 0;
};

}  // namespace

TwoLevelGrid build_two_level_grid(const TriangleMesh& mesh, const GridOptions& opt, BuildStats& stats) {
  TwoLevelGrid g;
  const size_t n = mesh.num_triangles();
  g.tris = copy_grid_triangles(mesh);
  g.empty = n == 0;
  if (g.empty) return g;

  const Aabb bounds = mesh.bounds();
  Vec3d lo, hi;
  padded_grid_box(bounds, lo, hi);
  const Vec3d extent = (bounds.hi - bounds.lo).cast<double>();
  const uint64_t budget = opt.budget_bytes();
  std::vector<uint32_t> all_ids(n);
  std::iota(all_ids.begin(), all_ids.end(), 0u);

  // Top level: at most 1/8 of the budget for its cells and its (temporary)
  // references.
  const uint64_t top_limit = std::max<uint64_t>(1, budget / 8 / sizeof(uint32_t));
  ChosenResolution top = choose_resolution(extent, static_cast<double>(n), opt.top_density, top_limit);
  CellLists top_lists;
  while (true) {
    g.top = make_dda_grid(lo, hi, top.res);
    if (build_cell_lists(g.top, opt.assign, g.tris, all_ids, top_limit, top_lists)) break;
    if (total_cells(top.res) == 1)
      throw std::runtime_error(fmt::format("grid2: a memory budget of {} MiB cannot hold the references of {} triangles",
                                           opt.budget_mib, n));
    top = choose_resolution(extent, static_cast<double>(n), top.lambda / 2, top_limit);
    top.capped = true;
  }
  std::vector<uint32_t>().swap(all_ids);

  // One sub-grid per non-empty top cell.
  std::vector<SubGridPlan> plans;
  for (uint32_t c = 0; c + 1 < top_lists.offsets.size(); ++c)
    if (top_lists.offsets[c + 1] != top_lists.offsets[c]) {
      SubGridPlan p;
      p.top_cell = c;
      plans.push_back(p);
    }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, plans.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k < r.end(); ++k) {
      const uint32_t c = plans[k].top_cell;
      const std::span<const uint32_t> ids(top_lists.refs.data() + top_lists.offsets[c],
                                          top_lists.offsets[c + 1] - top_lists.offsets[c]);
      plans[k] = plan_subgrid(g.top, c, ids, g.tris);
    }
  });

  // Sub-grids: their offsets may take half of the budget, their references
  // what is left; otherwise the sub-grid density is lowered and retried.
  const uint64_t top_bytes = total_cells(top.res) * sizeof(uint32_t) + plans.size() * sizeof(SubGrid);
  const uint64_t sub_cell_limit = std::max<uint64_t>(1, budget / 2 / sizeof(uint32_t));
  double lambda = opt.density;
  bool sub_capped = false;
  std::vector<CellLists> lists(plans.size());
  while (true) {
    uint64_t sub_cells = 0;
    for (auto& p : plans) {
      const uint32_t c = p.top_cell;
      const double count = top_lists.offsets[c + 1] - top_lists.offsets[c];
      p.res = resolution_by_density(p.extent, count, lambda);
      sub_cells += total_cells(p.res) + 1;
    }
    if (sub_cells > sub_cell_limit) {
      lambda *= std::min(0.5, static_cast<double>(sub_cell_limit) / static_cast<double>(sub_cells));
      sub_capped = true;
      continue;
    }
    const uint64_t left = budget > top_bytes + sub_cells * sizeof(uint32_t)
                              ? (budget - top_bytes - sub_cells * sizeof(uint32_t)) / sizeof(uint32_t)
                              : 0;
    std::atomic<uint64_t> refs{0};
    std::atomic<bool> over{false};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, plans.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) {
        if (over.load(std::memory_order_relaxed)) return;
        const SubGridPlan& p = plans[k];
        const uint32_t c = p.top_cell;
        const std::span<const uint32_t> ids(top_lists.refs.data() + top_lists.offsets[c],
                                            top_lists.offsets[c + 1] - top_lists.offsets[c]);
        const DdaGrid sub = make_dda_grid(p.lo, p.hi, p.res);
        if (!build_cell_lists(sub, opt.assign, g.tris, ids, left, lists[k]) ||
            refs.fetch_add(lists[k].refs.size()) + lists[k].refs.size() > left)
          over = true;
      }
    });
    if (!over) break;
    if (lambda < 1e-9)
      throw std::runtime_error(fmt::format("grid2: a memory budget of {} MiB cannot hold the references of {} triangles",
                                           opt.budget_mib, n));
    lambda /= 2;
    sub_capped = true;
    for (auto& l : lists) l = CellLists{};
  }
  if (top.capped || sub_capped) {
    warn_budget_capped("grid2", fmt::format("top={}, density={}", opt.top_density, opt.density),
                       fmt::format("top={:.4g} (res={}), density={:.4g}", top.lambda, format_grid_resolution(top.res), lambda),
                       opt.budget_mib);
  }

  // Concatenate: sub-grid k's offsets start at its base and point into the
  // one refs array.
  g.top_cells.assign(total_cells(top.res), kNoSubGrid);
  g.subgrids.resize(plans.size());
  uint64_t offsets_total = 0, refs_total = 0;
  std::vector<uint64_t> refs_base(plans.size());
  for (size_t k = 0; k < plans.size(); ++k) {
    g.top_cells[plans[k].top_cell] = static_cast<uint32_t>(k);
    g.subgrids[k].dda = make_dda_grid(plans[k].lo, plans[k].hi, plans[k].res);
    g.subgrids[k].offsets_base = static_cast<uint32_t>(offsets_total);
    refs_base[k] = refs_total;
    offsets_total += lists[k].offsets.size();
    refs_total += lists[k].refs.size();
  }
  if (offsets_total > UINT32_MAX || refs_total > UINT32_MAX)
    throw std::runtime_error("grid2: more than 2^32 cells or references");
  g.offsets.resize(offsets_total);
  g.refs.resize(refs_total);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, plans.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k < r.end(); ++k) {
      const uint32_t base = static_cast<uint32_t>(refs_base[k]);
      uint32_t* out = g.offsets.data() + g.subgrids[k].offsets_base;
      for (const uint32_t o : lists[k].offsets) *out++ = base + o;
      std::copy(lists[k].refs.begin(), lists[k].refs.end(), g.refs.begin() + static_cast<ptrdiff_t>(base));
      lists[k] = CellLists{};
    }
  });

  // Statistics over the sub-grids' cells.
  uint64_t sub_cells = 0, nonempty = 0;
  uint32_t max_per_cell = 0;
  for (const SubGrid& s : g.subgrids) {
    const uint64_t cells = s.dda.cells();
    const CellOccupancy occ = measure_occupancy(std::span<const uint32_t>(g.offsets.data() + s.offsets_base, cells + 1));
    sub_cells += cells;
    nonempty += occ.nonempty;
    max_per_cell = std::max(max_per_cell, occ.max_per_cell);
  }
  add_occupancy_stats(stats, total_cells(top.res) + sub_cells, nonempty, refs_total, max_per_cell, n);
  // Empty fraction and cells of the second level, where the triangles are.
  stats.extra["empty_fraction"] = sub_cells ? 1.0 - static_cast<double>(nonempty) / static_cast<double>(sub_cells) : 0.0;
  stats.extra["top_cells"] = static_cast<double>(total_cells(top.res));
  stats.extra["top_res_x"] = top.res[0];
  stats.extra["top_res_y"] = top.res[1];
  stats.extra["top_res_z"] = top.res[2];
  stats.extra["top_lambda"] = top.lambda;
  stats.extra["top_refs_per_triangle"] = static_cast<double>(top_lists.refs.size()) / static_cast<double>(n);
  stats.extra["subgrids"] = static_cast<double>(g.subgrids.size());
  stats.extra["sub_cells"] = static_cast<double>(sub_cells);
  stats.extra["lambda"] = lambda;
  stats.extra["lambda_requested"] = opt.density;
  stats.extra["budget_capped"] = (top.capped || sub_capped) ? 1.0 : 0.0;
  stats.max_depth = 2;
  stats.avg_depth = 2.0;
  stats.bytes = g.top_cells.capacity() * sizeof(uint32_t) + g.subgrids.capacity() * sizeof(SubGrid) +
                (g.offsets.capacity() + g.refs.capacity()) * sizeof(uint32_t) +
                g.tris.capacity() * sizeof(GridTriangle) + sizeof(TwoLevelGrid);
  return g;
}

}  // namespace raylab
