// The cells a triangle is assigned to (accel/core/grid/cell_overlap.h):
// assign=exact gives exactly the cells the overlap test accepts, within the
// bounding-box cells.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <tuple>

#include "accel/core/grid/cell_overlap.h"
#include "accel/core/tri_box_overlap.h"
#include "base/pcg.h"

namespace raylab {
namespace {

TEST(CellAssignment, ExactCellsEqualBruteForceSatAndAreWithinBbox) {
  const DdaGrid g = make_dda_grid(Vec3d(0, 0, 0), Vec3d(1, 2, 1), GridRes{12, 9, 16});
  Pcg32 rng(9, 1);
  size_t bbox_total = 0, exact_total = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3f c(rng.uniform(), 2 * rng.uniform(), rng.uniform());
    const float s = (i % 10 == 0) ? 1.5f : 0.3f;  // some triangles span many cells
    const Vec3f p0 = c + s * Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f);
    const Vec3f p1 = c + s * Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f);
    const Vec3f p2 = c + s * Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f);
    std::set<std::tuple<int, int, int>> exact, bbox, brute;
    for_each_assigned_cell(g, AssignMode::Exact, p0, p1, p2, [&](int x, int y, int z) {
      EXPECT_TRUE(exact.insert({x, y, z}).second) << "cell listed twice";
    });
    for_each_assigned_cell(g, AssignMode::Bbox, p0, p1, p2, [&](int x, int y, int z) { bbox.insert({x, y, z}); });
    const Vec3d margin = assignment_margin(g);
    for (int z = 0; z < g.res[2]; ++z)
      for (int y = 0; y < g.res[1]; ++y)
        for (int x = 0; x < g.res[0]; ++x) {
          const Vec3d lo(g.boundary(0, x) - margin[0], g.boundary(1, y) - margin[1], g.boundary(2, z) - margin[2]);
          const Vec3d hi(g.boundary(0, x + 1) + margin[0], g.boundary(1, y + 1) + margin[1],
                         g.boundary(2, z + 1) + margin[2]);
          if (triangle_box_overlap(lo, hi, p0.cast<double>(), p1.cast<double>(), p2.cast<double>()))
            brute.insert({x, y, z});
        }
    EXPECT_EQ(exact, brute) << "triangle " << i;
    EXPECT_TRUE(std::includes(bbox.begin(), bbox.end(), exact.begin(), exact.end()));
    bbox_total += bbox.size();
    exact_total += exact.size();
  }
  EXPECT_LT(exact_total, bbox_total);  // the exact test does drop cells
}

}  // namespace
}  // namespace raylab
