#include "accel/hgrid/build_hgrid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

namespace raylab {

namespace {

// The level's cell side: one formula for the whole build.
double level_cell(double finest, double ratio, int level) { return finest * std::pow(ratio, level); }

double largest_extent(const LeafTriangle& t) {
  const Vec3f lo = t.p0.cwiseMin(t.p1).cwiseMin(t.p2), hi = t.p0.cwiseMax(t.p1).cwiseMax(t.p2);
  return static_cast<double>((hi - lo).maxCoeff());
}

}  // namespace

namespace {

// Level of each triangle: the finest whose cell side covers its extent;
// sets g.finest_cell (the smallest extent, >= 2^-18 of the scene). Returns
// the coarsest level used.
int assign_levels(Hgrid& g, double ratio, double scene_side, std::vector<uint8_t>& level) {
  const size_t n = g.tris.size();
  std::vector<double> extent(n);
  tbb::parallel_for(size_t{0}, n, [&](size_t i) { extent[i] = largest_extent(g.tris[i]); });
  const double smallest = *std::min_element(extent.begin(), extent.end());
  g.finest_cell = std::max(smallest, scene_side * 0x1p-18);
  level.resize(n);
  int top = 0;
  for (size_t i = 0; i < n; ++i) {
    int l = extent[i] > g.finest_cell
                ? static_cast<int>(std::ceil(std::log(extent[i] / g.finest_cell) / std::log(ratio)))
                : 0;
    l = std::clamp(l, 0, kHgridMaxLevels - 1);
    while (l + 1 < kHgridMaxLevels && level_cell(g.finest_cell, ratio, l) < extent[i]) ++l;
    while (l > 0 && level_cell(g.finest_cell, ratio, l - 1) >= extent[i]) --l;
    level[i] = static_cast<uint8_t>(l);
    top = std::max(top, l);
  }
  return top;
}

// Pass 1: each level's box of occupied cells, on the level's lattice from lo,
// then one DDA grid per occupied level. Returns each level's slot in g.levels
// (-1: unoccupied).
std::vector<int> make_level_grids(Hgrid& g, const std::vector<uint8_t>& level, int top, const Vec3d& lo,
                                  double magnitude) {
  const bool pad = g.neighbours == HgridNeighbours::Pad;
  std::vector<std::array<int64_t, 6>> box(top + 1, {INT64_MAX, INT64_MAX, INT64_MAX, INT64_MIN, INT64_MIN, INT64_MIN});
  for (size_t i = 0; i < g.tris.size(); ++i) {
    const double cell = level_cell(g.finest_cell, g.ratio, level[i]);
    const LeafTriangle& t = g.tris[i];
    auto& b = box[level[i]];
    for (int a = 0; a < 3; ++a) {
      const double mn = std::min({t.p0[a], t.p1[a], t.p2[a]}), mx = std::max({t.p0[a], t.p1[a], t.p2[a]});
      int64_t c0, c1;
      if (pad) {
        c0 = c1 = static_cast<int64_t>(std::floor((0.5 * (mn + mx) - lo[a]) / cell));
      } else {
        const double margin = kCellMarginRelative * cell + kCellMarginUlps * magnitude;
        c0 = static_cast<int64_t>(std::floor((mn - margin - lo[a]) / cell));
        c1 = static_cast<int64_t>(std::floor((mx + margin - lo[a]) / cell));
      }
      b[a] = std::min(b[a], c0 - (pad ? 1 : 0));
      b[3 + a] = std::max(b[3 + a], c1 + (pad ? 1 : 0));
    }
  }
  std::vector<int> slot_of_level(top + 1, -1);
  for (int l = 0; l <= top; ++l) {
    if (box[l][0] == INT64_MAX) continue;
    const double cell = level_cell(g.finest_cell, g.ratio, l);
    double glo[3], cells[3] = {cell, cell, cell};
    int32_t res[3];
    for (int a = 0; a < 3; ++a) {
      glo[a] = lo[a] + static_cast<double>(box[l][a]) * cell;
      const int64_t r = box[l][3 + a] - box[l][a] + 1;
      if (r > (int64_t{1} << 19)) throw std::length_error("hgrid: a level spans more than 2^19 cells per axis");
      res[a] = static_cast<int32_t>(r);
    }
    slot_of_level[l] = static_cast<int>(g.levels.size());
    g.levels.push_back(HgridLevel{l, make_dda_grid_from_cells(glo, cells, res)});
    g.level_mask |= uint64_t{1} << l;
  }
  for (int a = 0; a < 3; ++a) {
    g.lo[a] = std::numeric_limits<double>::infinity();
    g.hi[a] = -std::numeric_limits<double>::infinity();
    for (const HgridLevel& L : g.levels) {
      g.lo[a] = std::min(g.lo[a], L.grid.lo[a]);
      g.hi[a] = std::max(g.hi[a], L.grid.hi[a]);
    }
  }
  return slot_of_level;
}

// Pass 2: (key, triangle) for every cell a triangle is listed in, using the
// level grids' own coordinates (the walk's), sorted by key.
std::vector<std::pair<uint64_t, uint32_t>> cell_references(const Hgrid& g, const std::vector<uint8_t>& level,
                                                           const std::vector<int>& slot_of_level) {
  const bool pad = g.neighbours == HgridNeighbours::Pad;
  std::vector<std::pair<uint64_t, uint32_t>> pairs;
  pairs.reserve(g.tris.size() * (pad ? 1 : 4));
  for (size_t i = 0; i < g.tris.size(); ++i) {
    const HgridLevel& L = g.levels[slot_of_level[level[i]]];
    const DdaGrid& dg = L.grid;
    const LeafTriangle& t = g.tris[i];
    int32_t c0[3], c1[3];
    for (int a = 0; a < 3; ++a) {
      const double mn = std::min({t.p0[a], t.p1[a], t.p2[a]}), mx = std::max({t.p0[a], t.p1[a], t.p2[a]});
      if (pad) {
        c0[a] = c1[a] = dg.coord(a, 0.5 * (mn + mx));
      } else {
        const Vec3d margin = assignment_margin(dg);
        c0[a] = dg.coord(a, mn - margin[a]);
        c1[a] = dg.coord(a, mx + margin[a]);
      }
    }
    for (int32_t z = c0[2]; z <= c1[2]; ++z)
      for (int32_t y = c0[1]; y <= c1[1]; ++y)
        for (int32_t x = c0[0]; x <= c1[0]; ++x)
          pairs.emplace_back(hgrid_key(L.level, dg.index(x, y, z)), static_cast<uint32_t>(i));
  }
  tbb::parallel_sort(pairs.begin(), pairs.end());
  return pairs;
}

void report_hgrid_stats(const Hgrid& g, int top, size_t references, size_t occupied, const CellTableFigures& table,
                        BuildStats& stats) {
  double walkable = 0.0;
  for (const HgridLevel& L : g.levels) walkable += static_cast<double>(L.grid.cells());
  stats.nodes = occupied;
  stats.leaves = occupied;
  stats.max_depth = top;
  stats.bytes = g.cells.bytes() + g.refs.size() * sizeof(uint32_t) + g.tris.size() * sizeof(LeafTriangle) +
                g.levels.size() * sizeof(HgridLevel);
  stats.extra["occupied_levels"] = static_cast<double>(g.levels.size());
  stats.extra["level_span"] = static_cast<double>(top + 1);
  stats.extra["finest_cell"] = g.finest_cell;
  stats.extra["references"] = static_cast<double>(references);
  stats.extra["refs_per_triangle"] = static_cast<double>(references) / static_cast<double>(g.tris.size());
  stats.extra["walkable_cells"] = walkable;
  stats.extra["max_cell_size"] = static_cast<double>(table.max_list);
  stats.extra["max_probes"] = static_cast<double>(table.max_probes);
}

}  // namespace

Hgrid build_hgrid(const TriangleMesh& mesh, const HgridOptions& opt, BuildStats& stats) {
  Hgrid g;
  g.ratio = opt.ratio;
  g.neighbours = opt.neighbours;
  const size_t n = mesh.num_triangles();
  if (n >= (size_t{1} << 32) - 1) throw std::length_error("hgrid: more than 2^32 - 2 triangles");
  g.tris = copy_leaf_triangles(mesh);
  g.empty = n == 0;
  if (g.empty) return g;

  Vec3d lo, hi;
  padded_grid_box(mesh.bounds(), lo, hi);
  const double scene_side = (hi - lo).maxCoeff();
  const double magnitude = std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff());

  std::vector<uint8_t> level;
  const int top = assign_levels(g, opt.ratio, scene_side, level);
  const std::vector<int> slot_of_level = make_level_grids(g, level, top, lo, magnitude);
  const std::vector<std::pair<uint64_t, uint32_t>> pairs = cell_references(g, level, slot_of_level);
  const auto key = [](const std::pair<uint64_t, uint32_t>& p) { return p.first; };
  const size_t occupied = count_key_runs(pairs, key);
  if (pairs.size() > UINT32_MAX) throw std::length_error("hgrid: more than 2^32 cell references");
  const CellTableFigures table = fill_cell_table(
      pairs, occupied, key, [](const std::pair<uint64_t, uint32_t>& p) { return p.second; }, g.cells, g.refs);
  report_hgrid_stats(g, top, pairs.size(), occupied, table, stats);
  return g;
}

}  // namespace raylab
