#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "accel/grid/grid_build_start.h"
#include "accel/core/grid/grid_stats.h"
#include "accel/grid/implicit_grid.h"

namespace raylab {

ImplicitGrid build_implicit_grid(const TriangleMesh& mesh, const GridOptions& opt, BuildStats& stats) {
  ImplicitGrid g;
  GridBuildStart start;
  if (!start_grid_build(mesh, opt, g, start)) return g;
  g.words = (start.triangles + 63) / 64;
  // Slab bits: (nx + ny + nz) * words * 8 bytes must fit the budget.
  const uint64_t max_cells = std::max<uint64_t>(1, start.budget / 2 / sizeof(uint32_t) - 1);
  ChosenResolution chosen = start.first_resolution(opt, max_cells);
  while (true) {
    const uint64_t slabs = static_cast<uint64_t>(chosen.res[0]) + chosen.res[1] + chosen.res[2];
    if (slabs * g.words * sizeof(uint64_t) <= start.budget) break;
    start.shrink(opt, chosen, max_cells, "grid:storage=implicit", "slab bits");
  }
  start.warn_if_capped(opt, chosen, "grid:storage=implicit");
  g.dda = make_dda_grid(start.lo, start.hi, chosen.res);
  const size_t slabs = static_cast<size_t>(g.dda.res[0]) + g.dda.res[1] + g.dda.res[2];
  g.bits.assign(slabs * g.words, 0);
  const Vec3d margin = assignment_margin(g.dda);
  // Each axis in parallel over slabs would race on words; triangles are
  // processed in word-sized runs instead, so every task owns its words.
  tbb::parallel_for(size_t{0}, g.words, [&](size_t w) {
    const size_t end = std::min(start.triangles, (w + 1) * 64);
    for (size_t i = w * 64; i < end; ++i) {
      const LeafTriangle& t = g.tris[i];
      for (int a = 0; a < 3; ++a) {
        const double mn = std::min({t.p0[a], t.p1[a], t.p2[a]}) - margin[a];
        const double mx = std::max({t.p0[a], t.p1[a], t.p2[a]}) + margin[a];
        const int32_t c0 = g.dda.coord(a, mn), c1 = g.dda.coord(a, mx);
        for (int32_t c = c0; c <= c1; ++c) g.bits[g.slab(a, c) * g.words + w] |= uint64_t{1} << (i - w * 64);
      }
    }
  });
  g.word_lo.assign(slabs, 0);
  g.word_hi.assign(slabs, 0);
  uint64_t set_bits = 0;
  for (size_t s = 0; s < slabs; ++s) {
    const uint64_t* row = g.bits.data() + s * g.words;
    size_t lo = 0, hi = g.words;
    while (lo < hi && row[lo] == 0) ++lo;
    while (hi > lo && row[hi - 1] == 0) --hi;
    g.word_lo[s] = static_cast<uint32_t>(lo);
    g.word_hi[s] = static_cast<uint32_t>(hi);
    for (size_t w = lo; w < hi; ++w) set_bits += static_cast<uint64_t>(std::popcount(row[w]));
  }
  // Cell figures as the other grids report them would need every cell's
  // AND; report the slab figures instead (the bbox assignment's references
  // are the product of the slab ranges).
  stats.nodes = g.dda.cells();
  stats.leaves = 0;
  stats.max_depth = 1;
  stats.avg_depth = 1.0;
  add_resolution_stats(stats, chosen.res, opt.res ? 0.0 : chosen.lambda, opt.res ? 0.0 : opt.density);
  stats.extra["cells"] = static_cast<double>(g.dda.cells());
  stats.extra["budget_capped"] = chosen.capped ? 1.0 : 0.0;
  stats.extra["slabs"] = static_cast<double>(slabs);
  stats.extra["slab_bits_set"] = static_cast<double>(set_bits);
  stats.extra["slab_words"] = static_cast<double>(g.words);
  stats.bytes = g.bits.size() * sizeof(uint64_t) + (g.word_lo.size() + g.word_hi.size()) * sizeof(uint32_t) +
                g.tris.capacity() * sizeof(LeafTriangle) + sizeof(ImplicitGrid);
  return g;
}

}  // namespace raylab
