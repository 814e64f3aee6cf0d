#include "accel/hybrid/top_grid.h"

#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "accel/core/grid/grid_resolution.h"

namespace raylab {

TopGrid build_top_grid(const TriangleMesh& mesh, double density, bool with_lists) {
  TopGrid g;
  const size_t n = mesh.num_triangles();
  g.tris = copy_leaf_triangles(mesh);
  g.empty = n == 0;
  if (g.empty) return g;
  Vec3d lo, hi;
  padded_grid_box(mesh.bounds(), lo, hi);
  const ChosenResolution chosen = choose_resolution(hi - lo, static_cast<double>(n), density, kTopGridMaxCells);
  g.density = chosen.lambda;
  g.dda = make_dda_grid(lo, hi, chosen.res);
  if (!with_lists) return g;
  std::vector<uint32_t> ids(n);
  std::iota(ids.begin(), ids.end(), 0u);
  // The top grid is coarse, so references stay near one per triangle; the
  // limit only guards 32-bit offsets.
  if (!build_cell_lists(g.dda, AssignMode::Exact, g.tris, ids, std::numeric_limits<uint32_t>::max() - 1, g.lists))
    throw std::runtime_error("hybrid: more than 2^32 triangle references in the top grid (lower top)");
  return g;
}

Aabb top_cell_box(const DdaGrid& g, int32_t x, int32_t y, int32_t z) {
  const Vec3d margin = assignment_margin(g);
  const int32_t c[3] = {x, y, z};
  Aabb b;
  for (int a = 0; a < 3; ++a) {
    const double lo = g.boundary(a, c[a]) - margin[a];
    const double hi = g.boundary(a, c[a] + 1) + margin[a];
    float flo = static_cast<float>(lo), fhi = static_cast<float>(hi);
    if (static_cast<double>(flo) > lo) flo = std::nextafter(flo, -std::numeric_limits<float>::infinity());
    if (static_cast<double>(fhi) < hi) fhi = std::nextafter(fhi, std::numeric_limits<float>::infinity());
    b.lo[a] = flo;
    b.hi[a] = fhi;
  }
  return b;
}

}  // namespace raylab
