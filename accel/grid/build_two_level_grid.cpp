#include "accel/grid/two_level_grid.h"

#include <algorithm>
#include <atomic>
#include <numeric>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "accel/grid/cell_blocks.h"
#include "accel/core/grid/cell_lists.h"
#include "accel/grid/grid_build_start.h"
#include "accel/core/grid/grid_stats.h"

namespace raylab {

namespace {

// Sub-grids whose triangles are large compared with their cells (stacked
// copies, a few big triangles) would list every triangle in most cells. A
// sub-grid is coarsened until its bounding-box estimate of references is at
// most this many per triangle and unit of density.
constexpr double kMaxBboxRefsPerTriangle = 16.0;

// A triangle is large in a top cell when its bounds, clipped to the cell,
// span at least this fraction of the cell along two axes or more.
constexpr double kLargeFraction = 0.5;

struct SubGridPlan {
  uint32_t top_cell = 0;
  std::vector<uint32_t> small, large;            // the top cell's triangles, split
  Vec3d lo = Vec3d::Zero(), hi = Vec3d::Zero();  // padded box of the sub-grid
  Vec3d extent = Vec3d::Zero();                  // unpadded extent, for the resolution rule
  TopCellContent content{};
};

// Splits the top cell's triangles into large and small, and boxes the small
// ones: their bounds clipped to the cell (enlarged by the top grid's
// assignment margin, as the assignment was), then padded like a grid box.
// `whole_cell` (sub=cell, the published rule): every triangle is small and
// the box is the whole (enlarged) cell.
void plan_box(const DdaGrid& top, std::span<const LeafTriangle> tris, std::span<const uint32_t> ids, bool whole_cell,
              SubGridPlan& p) {
  const int64_t cell = p.top_cell;
  const int64_t c[3] = {cell % top.res[0], (cell / top.res[0]) % top.res[1],
                        cell / (static_cast<int64_t>(top.res[0]) * top.res[1])};
  const Vec3d margin = assignment_margin(top);
  Vec3d cell_lo, cell_hi;
  for (int a = 0; a < 3; ++a) {
    cell_lo[a] = top.boundary(a, c[a]) - margin[a];
    cell_hi[a] = top.boundary(a, c[a] + 1) + margin[a];
  }
  Vec3d blo = Vec3d::Constant(std::numeric_limits<double>::infinity());
  Vec3d bhi = -blo;
  if (whole_cell) {
    p.small.assign(ids.begin(), ids.end());
    blo = cell_lo;
    bhi = cell_hi;
  }
  for (const uint32_t id : whole_cell ? std::span<const uint32_t>() : ids) {
    const LeafTriangle& t = tris[id];
    Vec3d tlo = t.p0.cast<double>().cwiseMin(t.p1.cast<double>()).cwiseMin(t.p2.cast<double>());
    Vec3d thi = t.p0.cast<double>().cwiseMax(t.p1.cast<double>()).cwiseMax(t.p2.cast<double>());
    tlo = tlo.cwiseMax(cell_lo);
    thi = thi.cwiseMin(cell_hi);
    int spanning = 0;
    for (int a = 0; a < 3; ++a) spanning += thi[a] - tlo[a] >= kLargeFraction * top.cell[a];
    if (spanning >= 2) {
      p.large.push_back(id);
    } else {
      p.small.push_back(id);
      blo = blo.cwiseMin(tlo);
      bhi = bhi.cwiseMax(thi);
    }
  }
  if (p.small.empty()) return;
  for (int a = 0; a < 3; ++a)
    if (bhi[a] < blo[a]) bhi[a] = blo[a];  // only possible through rounding
  p.extent = bhi - blo;
  // Padded like a grid box, with the top grid's error scale: rays reach the
  // sub-grid from anywhere in the top grid.
  const double largest_top_cell = std::max({top.cell[0], top.cell[1], top.cell[2]});
  const double pad =
      std::max({1e-5 * p.extent.maxCoeff(), 1e-7 * largest_top_cell, kCellMarginUlps * top.error_scale, 1e-30});
  p.lo = blo.array() - pad;
  p.hi = bhi.array() + pad;
}

void set_resolution(SubGridPlan& p, const GridRes& res) {
  for (int a = 0; a < 3; ++a) {
    p.content.lo[a] = p.lo[a];
    p.content.cell[a] = (p.hi[a] - p.lo[a]) / res[a];
    p.content.res[a] = res[a];
  }
}

// A sub-grid as its builder sees it: its cells, with the top grid's error
// scale (the margin must cover rays from anywhere in the top grid).
DdaGrid subgrid_dda(const TopCellContent& content, const DdaGrid& top) {
  DdaGrid d = content.dda();
  d.error_scale = top.error_scale;
  return d;
}

// Cells covered by the triangles' bounding boxes (an upper bound of the
// references the sub-grid will hold).
double bbox_refs(const SubGridPlan& p, std::span<const LeafTriangle> tris) {
  const DdaGrid g = p.content.dda();
  double sum = 0.0;
  for (const uint32_t id : p.small) {
    const LeafTriangle& t = tris[id];
    double cells = 1.0;
    for (int a = 0; a < 3; ++a) {
      const int32_t lo = g.coord(a, std::min({t.p0[a], t.p1[a], t.p2[a]}));
      const int32_t hi = g.coord(a, std::max({t.p0[a], t.p1[a], t.p2[a]}));
      cells *= hi - lo + 1;
    }
    sum += cells;
  }
  return sum;
}

// The n^(1/3) rule for the top cell's triangles, coarsened when they are
// large compared with the cells (not with the published rule, sub=cell).
void size_subgrid(SubGridPlan& p, double lambda, bool whole_cell, std::span<const LeafTriangle> tris) {
  if (p.small.empty()) return;  // no sub-grid: res stays 0
  const double n = static_cast<double>(p.small.size());
  if (whole_cell) {
    set_resolution(p, resolution_by_density(p.extent, n, lambda));
    return;
  }
  const double limit = kMaxBboxRefsPerTriangle * std::max(1.0, lambda) * n;
  for (double l = lambda;; l *= 0.5) {
    const GridRes res = resolution_by_density(p.extent, n, l);
    set_resolution(p, res);
    if (total_cells(res) == 1 || bbox_refs(p, tris) <= limit) return;
  }
}

std::runtime_error budget_error(const GridOptions& opt, size_t n) {
  return std::runtime_error(
      fmt::format("grid2: a memory budget of {} MiB cannot hold the references of {} triangles", opt.budget_mib, n));
}

}  // namespace

namespace {

// The top level: a coarse grid and its cell lists (they live only during the
// build). The top cells (4 bytes each) get at most 1/8 of the budget, the
// top-level references at most half; the density halves until they fit.
ChosenResolution build_top_level(const GridBuildStart& start, const GridOptions& opt, TwoLevelGrid& g,
                                 CellLists& top_lists) {
  const size_t n = start.triangles;
  std::vector<uint32_t> all_ids(n);
  std::iota(all_ids.begin(), all_ids.end(), 0u);
  const uint64_t top_cell_limit = std::max<uint64_t>(1, start.budget / 8 / sizeof(uint32_t));
  const uint64_t top_ref_limit = start.budget / 2 / sizeof(uint32_t);
  ChosenResolution top = choose_resolution(start.extent, static_cast<double>(n), opt.top_density, top_cell_limit);
  while (true) {
    g.top = make_dda_grid(start.lo, start.hi, top.res);
    if (build_cell_lists(g.top, opt.assign, g.tris, all_ids, top_ref_limit, top_lists)) return top;
    if (total_cells(top.res) == 1) throw budget_error(opt, n);
    top = choose_resolution(start.extent, static_cast<double>(n), top.lambda / 2, top_cell_limit);
    top.capped = true;
  }
}

// Per non-empty top cell: its large triangles, and the box of the part of
// the cell its small triangles occupy.
std::vector<SubGridPlan> plan_top_cells(const TwoLevelGrid& g, const CellLists& top_lists, bool whole_cell) {
  std::vector<SubGridPlan> plans;
  for (uint32_t c = 0; c + 1 < top_lists.offsets.size(); ++c) {
    if (top_lists.offsets[c + 1] == top_lists.offsets[c]) continue;
    plans.emplace_back();
    plans.back().top_cell = c;
  }
  tbb::parallel_for(tbb::blocked_range<size_t>(0, plans.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k < r.end(); ++k) {
      const uint32_t c = plans[k].top_cell;
      const std::span<const uint32_t> ids(top_lists.refs.data() + top_lists.offsets[c],
                                          top_lists.offsets[c + 1] - top_lists.offsets[c]);
      plan_box(g.top, g.tris, ids, whole_cell, plans[k]);
    }
  });
  return plans;
}

// Sizes every sub-grid by the density and fills its cell lists; while the
// final structure (top_bytes already spent) would exceed the budget, the
// density is lowered. Returns the density used.
double fill_subgrids(std::vector<SubGridPlan>& plans, const TwoLevelGrid& g, const GridOptions& opt, uint64_t budget,
                     uint64_t top_bytes, size_t n, std::vector<CellLists>& lists, bool& capped) {
  double lambda = opt.density;
  lists.assign(plans.size(), CellLists{});
  while (true) {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, plans.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) size_subgrid(plans[k], lambda, opt.whole_cell_subgrids, g.tris);
    });
    uint64_t sub_offsets = 0;
    for (const auto& p : plans)
      if (p.content.has_subgrid()) sub_offsets += p.content.dda().cells() + 1;
    const uint64_t fixed = top_bytes + sub_offsets * sizeof(uint32_t);
    if (fixed >= budget) {
      // Cells alone exceed the budget: scale the density by the excess.
      if (lambda < 1e-9) throw budget_error(opt, n);
      lambda *= std::min(0.5, static_cast<double>(budget - top_bytes) / static_cast<double>(sub_offsets * sizeof(uint32_t)));
      capped = true;
      continue;
    }
    const uint64_t ref_limit = (budget - fixed) / reference_bytes(opt.leaf_blocks());
    std::atomic<uint64_t> refs{0};
    std::atomic<bool> over{false};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, plans.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t k = r.begin(); k < r.end(); ++k) {
        if (over.load(std::memory_order_relaxed)) return;
        if (!plans[k].content.has_subgrid()) continue;
        if (!build_cell_lists(subgrid_dda(plans[k].content, g.top), opt.assign, g.tris, plans[k].small, ref_limit, lists[k]) ||
            refs.fetch_add(lists[k].refs.size()) + lists[k].refs.size() > ref_limit)
          over = true;
      }
    });
    if (!over && opt.leaf_blocks()) {
      uint64_t blocks = 0;
      for (const CellLists& l : lists) blocks += blocks_of_runs(l.offsets);
      over = blocks * sizeof(CellTriangleBlock) > budget - fixed;
    }
    if (!over) return lambda;
    if (lambda < 1e-9) throw budget_error(opt, n);
    lambda /= 2;
    capped = true;
    for (auto& l : lists) l = CellLists{};
  }
}

// Concatenates: top cell k's large triangles, then its sub-grid's
// references, in the one refs array; the sub-grid's offsets start at its
// base in the one offsets array and point into refs.
void concatenate_levels(const ChosenResolution& top, const std::vector<SubGridPlan>& plans,
                        std::vector<CellLists>& lists, TwoLevelGrid& g) {
  g.top_cells.assign(total_cells(top.res), kEmptyTopCell);
  g.contents.resize(plans.size());
  uint64_t offsets_total = 0, refs_total = 0;
  std::vector<uint64_t> refs_base(plans.size());
  for (size_t k = 0; k < plans.size(); ++k) {
    g.top_cells[plans[k].top_cell] = static_cast<uint32_t>(k);
    TopCellContent& content = g.contents[k];
    content = plans[k].content;
    content.offsets_base = static_cast<uint32_t>(offsets_total);
    content.large_begin = static_cast<uint32_t>(refs_total);
    content.large_count = static_cast<uint32_t>(plans[k].large.size());
    refs_base[k] = refs_total + plans[k].large.size();
    offsets_total += lists[k].offsets.size();
    refs_total += plans[k].large.size() + lists[k].refs.size();
  }
  if (offsets_total > UINT32_MAX || refs_total > UINT32_MAX)
    throw std::runtime_error("grid2: more than 2^32 cells or references");
  g.offsets.resize(offsets_total);
  g.refs.resize(refs_total);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, plans.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t k = r.begin(); k < r.end(); ++k) {
      const TopCellContent& content = g.contents[k];
      std::copy(plans[k].large.begin(), plans[k].large.end(), g.refs.begin() + content.large_begin);
      const uint32_t base = static_cast<uint32_t>(refs_base[k]);
      uint32_t* out = g.offsets.data() + content.offsets_base;
      for (const uint32_t o : lists[k].offsets) *out++ = base + o;
      std::copy(lists[k].refs.begin(), lists[k].refs.end(), g.refs.begin() + static_cast<ptrdiff_t>(base));
      lists[k] = CellLists{};
    }
  });
}

// Statistics: cells of both levels; occupancy of the second level, where
// the triangles are.
void add_two_level_stats(const TwoLevelGrid& g, const ChosenResolution& top, size_t top_refs, uint64_t large_refs,
                         double lambda, bool capped, const GridOptions& opt, size_t n, BuildStats& stats) {
  uint64_t sub_cells = 0, nonempty = 0;
  uint32_t max_per_cell = 0;
  uint64_t subgrids = 0;
  for (const TopCellContent& s : g.contents) {
    if (!s.has_subgrid()) continue;
    ++subgrids;
    const uint64_t cells = total_cells(GridRes{s.res[0], s.res[1], s.res[2]});
    const CellOccupancy occ = measure_occupancy(std::span<const uint32_t>(g.offsets.data() + s.offsets_base, cells + 1));
    sub_cells += cells;
    nonempty += occ.nonempty;
    max_per_cell = std::max(max_per_cell, occ.max_per_cell);
  }
  add_occupancy_stats(stats, total_cells(top.res) + sub_cells, nonempty, g.refs.size(), max_per_cell, n);
  stats.extra["empty_fraction"] = sub_cells ? 1.0 - static_cast<double>(nonempty) / static_cast<double>(sub_cells) : 0.0;
  stats.extra["top_cells"] = static_cast<double>(total_cells(top.res));
  stats.extra["top_res_x"] = top.res[0];
  stats.extra["top_res_y"] = top.res[1];
  stats.extra["top_res_z"] = top.res[2];
  stats.extra["top_lambda"] = top.lambda;
  stats.extra["top_refs_per_triangle"] = static_cast<double>(top_refs) / static_cast<double>(n);
  stats.extra["subgrids"] = static_cast<double>(subgrids);
  stats.extra["large_refs"] = static_cast<double>(large_refs);
  stats.extra["sub_cells"] = static_cast<double>(sub_cells);
  stats.extra["lambda"] = lambda;
  stats.extra["lambda_requested"] = opt.density;
  stats.extra["budget_capped"] = capped ? 1.0 : 0.0;
  stats.max_depth = 2;
  stats.avg_depth = 2.0;
  stats.bytes = g.top_cells.capacity() * sizeof(uint32_t) + g.contents.capacity() * sizeof(TopCellContent) +
                (g.offsets.capacity() + g.refs.capacity()) * sizeof(uint32_t) +
                g.tris.capacity() * sizeof(LeafTriangle) + sizeof(TwoLevelGrid);
}

// The cells' references as SIMD blocks (cell_blocks.h): every run (a top
// cell's large triangles, a sub-grid cell's list) becomes a run of blocks.
void to_blocks(const TriangleMesh& mesh, TwoLevelGrid& g, BuildStats& stats) {
  std::vector<uint32_t> starts(g.offsets);
  for (const TopCellContent& c : g.contents) starts.push_back(c.large_begin);
  CellBlocks cb = to_cell_blocks(mesh, g.refs, starts);
  for (uint32_t& o : g.offsets) o = cb.block_at[o];
  for (TopCellContent& c : g.contents) {
    const uint32_t first = cb.block_at[c.large_begin];
    c.large_count = cb.block_at[c.large_begin + c.large_count] - first;
    c.large_begin = first;
  }
  stats.bytes += cb.blocks.capacity() * sizeof(CellTriangleBlock);
  stats.bytes -= g.refs.capacity() * sizeof(uint32_t) + g.tris.capacity() * sizeof(LeafTriangle);
  g.blocks = std::move(cb.blocks);
  std::vector<uint32_t>().swap(g.refs);
  std::vector<LeafTriangle>().swap(g.tris);
}

}  // namespace

// The final structure (top cells, sub-grid records, sub-grid cells and
// references) must fit the whole budget.
TwoLevelGrid build_two_level_grid(const TriangleMesh& mesh, const GridOptions& opt, BuildStats& stats) {
  TwoLevelGrid g;
  GridBuildStart start;
  if (!start_grid_build(mesh, opt, g, start)) return g;
  const size_t n = start.triangles;
  CellLists top_lists;
  const ChosenResolution top = build_top_level(start, opt, g, top_lists);
  std::vector<SubGridPlan> plans = plan_top_cells(g, top_lists, opt.whole_cell_subgrids);
  uint64_t large_refs = 0, large_blocks = 0;
  for (const auto& p : plans) {
    large_refs += p.large.size();
    large_blocks += cell_block_count(static_cast<uint32_t>(p.large.size()));
  }
  const uint64_t top_bytes = total_cells(top.res) * sizeof(uint32_t) + plans.size() * sizeof(TopCellContent) +
                             (opt.leaf_blocks() ? large_blocks * sizeof(CellTriangleBlock) : large_refs * sizeof(uint32_t));
  if (top_bytes >= start.budget) throw budget_error(opt, n);
  bool sub_capped = false;
  std::vector<CellLists> lists;
  const double lambda = fill_subgrids(plans, g, opt, start.budget, top_bytes, n, lists, sub_capped);
  if (top.capped || sub_capped) {
    warn_budget_capped("grid2", fmt::format("top={}, density={}", opt.top_density, opt.density),
                       fmt::format("top={:.4g} (res={}), density={:.4g}", top.lambda, format_grid_resolution(top.res), lambda),
                       opt.budget_mib);
  }
  concatenate_levels(top, plans, lists, g);
  add_two_level_stats(g, top, top_lists.refs.size(), large_refs, lambda, top.capped || sub_capped, opt, n, stats);
  if (opt.leaf_blocks()) to_blocks(mesh, g, stats);
  stats.extra["cell_blocks"] = static_cast<double>(g.blocks.size());
  return g;
}

}  // namespace raylab
