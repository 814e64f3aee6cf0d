// The 3D-DDA (accel/core/grid/dda.h) on its own: cells in order along axes,
// signed zeros, origins on cell boundaries, windows, random rays, and the
// skipping walk over the grids' clearance (accel/grid/cell_clearance.h).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <set>
#include <tuple>
#include <vector>

#include "accel/core/grid/dda.h"
#include "accel/grid/cell_clearance.h"
#include "base/pcg.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

struct Visit {
  int64_t cell;
  double t_enter, t_exit;
};

std::vector<Visit> walk(const DdaGrid& g, const Ray& r) {
  std::vector<Visit> out;
  const DdaRay dr(r);
  double t0 = r.tmin, t1 = r.tmax;
  if (!dda_clip(dr, g.lo, g.hi, t0, t1)) return out;
  dda_walk(g, dr, t0, t1, [&](int64_t c, double te, double tx) {
    out.push_back({c, te, tx});
    return false;
  });
  return out;
}

std::tuple<int, int, int> coords(const DdaGrid& g, int64_t c) {
  return {static_cast<int>(c % g.res[0]), static_cast<int>((c / g.res[0]) % g.res[1]),
          static_cast<int>(c / (static_cast<int64_t>(g.res[0]) * g.res[1]))};
}

// Checks the walk's invariants and returns the cells visited for a positive length.
std::vector<int64_t> check_walk(const DdaGrid& g, const Ray& r, const std::vector<Visit>& v) {
  std::vector<int64_t> cells;
  for (size_t i = 0; i < v.size(); ++i) {
    EXPECT_LE(v[i].t_enter, v[i].t_exit + 1e-12) << "visit " << i;
    if (i > 0) {
      EXPECT_EQ(v[i].t_enter, v[i - 1].t_exit) << "visit " << i;
      const auto [x0, y0, z0] = coords(g, v[i - 1].cell);
      const auto [x1, y1, z1] = coords(g, v[i].cell);
      EXPECT_EQ(std::abs(x1 - x0) + std::abs(y1 - y0) + std::abs(z1 - z0), 1) << "not face-adjacent at " << i;
    }
    if (v[i].t_exit > v[i].t_enter) cells.push_back(v[i].cell);
    // The middle of the visited interval lies in the visited cell.
    if (v[i].t_exit > v[i].t_enter && std::isfinite(v[i].t_exit)) {
      const double tm = 0.5 * (v[i].t_enter + v[i].t_exit);
      const auto [x, y, z] = coords(g, v[i].cell);
      const int c[3] = {x, y, z};
      for (int a = 0; a < 3; ++a) {
        const double p = static_cast<double>(r.org[a]) + tm * static_cast<double>(r.dir[a]);
        EXPECT_GE(p, g.boundary(a, c[a]) - 1e-9) << "visit " << i << " axis " << a;
        EXPECT_LE(p, g.boundary(a, c[a] + 1) + 1e-9) << "visit " << i << " axis " << a;
      }
    }
  }
  return cells;
}

const DdaGrid kUnitGrid = make_dda_grid(Vec3d(0, 0, 0), Vec3d(4, 4, 4), GridRes{4, 4, 4});

TEST(Dda, AxisParallelRayVisitsItsRowInOrder) {
  const auto v = walk(kUnitGrid, Ray(Vec3f(-1, 1.5f, 2.5f), Vec3f(1, 0, 0)));
  const auto cells = check_walk(kUnitGrid, Ray(Vec3f(-1, 1.5f, 2.5f), Vec3f(1, 0, 0)), v);
  ASSERT_EQ(cells.size(), 4u);
  for (int x = 0; x < 4; ++x) EXPECT_EQ(cells[x], kUnitGrid.index(x, 1, 2));
  EXPECT_DOUBLE_EQ(v.front().t_enter, 1.0);
  EXPECT_DOUBLE_EQ(v.back().t_exit, 5.0);
  // Backwards along -y.
  const Ray back(Vec3f(0.5f, 10, 3.5f), Vec3f(0, -2, 0));
  const auto cb = check_walk(kUnitGrid, back, walk(kUnitGrid, back));
  ASSERT_EQ(cb.size(), 4u);
  for (int y = 0; y < 4; ++y) EXPECT_EQ(cb[y], kUnitGrid.index(0, 3 - y, 3));
}

TEST(Dda, PlusAndMinusZeroComponentsWalkTheSameCells) {
  for (const float zero : {0.0f, -0.0f}) {
    const Ray r(Vec3f(-1, 2.5f, 0.5f), Vec3f(1, zero, zero));
    const auto cells = check_walk(kUnitGrid, r, walk(kUnitGrid, r));
    ASSERT_EQ(cells.size(), 4u) << "zero sign " << std::signbit(zero);
    for (int x = 0; x < 4; ++x) EXPECT_EQ(cells[x], kUnitGrid.index(x, 2, 0));
    const Ray r2(Vec3f(1.5f, 1.5f, 7), Vec3f(zero, zero, -1));
    const auto c2 = check_walk(kUnitGrid, r2, walk(kUnitGrid, r2));
    ASSERT_EQ(c2.size(), 4u);
    EXPECT_EQ(c2.front(), kUnitGrid.index(1, 1, 3));
  }
}

TEST(Dda, OriginsExactlyOnCellBoundaries) {
  // Starting on the plane x = 2 going +x: first cell with length is x = 2.
  const Ray fwd(Vec3f(2, 0.5f, 0.5f), Vec3f(1, 0, 0));
  auto cells = check_walk(kUnitGrid, fwd, walk(kUnitGrid, fwd));
  ASSERT_EQ(cells.size(), 2u);
  EXPECT_EQ(cells[0], kUnitGrid.index(2, 0, 0));
  // The same origin going -x: cells 1 and 0.
  const Ray bwd(Vec3f(2, 0.5f, 0.5f), Vec3f(-1, 0, 0));
  cells = check_walk(kUnitGrid, bwd, walk(kUnitGrid, bwd));
  ASSERT_EQ(cells.size(), 2u);
  EXPECT_EQ(cells[0], kUnitGrid.index(1, 0, 0));
  EXPECT_EQ(cells[1], kUnitGrid.index(0, 0, 0));
  // On a corner of cells going diagonally: 6-connected steps through corners.
  const Ray diag(Vec3f(1, 1, 1), Vec3f(1, 1, 1));
  const auto v = walk(kUnitGrid, diag);
  cells = check_walk(kUnitGrid, diag, v);
  ASSERT_EQ(cells.size(), 3u);
  EXPECT_EQ(cells[0], kUnitGrid.index(1, 1, 1));
  EXPECT_EQ(cells[1], kUnitGrid.index(2, 2, 2));
  EXPECT_EQ(cells[2], kUnitGrid.index(3, 3, 3));
  // A ray lying in the boundary plane y = 2 (zero y direction) stays in one row.
  const Ray plane(Vec3f(-1, 2, 0.5f), Vec3f(1, 0, 0));
  cells = check_walk(kUnitGrid, plane, walk(kUnitGrid, plane));
  ASSERT_EQ(cells.size(), 4u);
  // On the outer boundary of the grid (x = 4 exactly, going -x) starts inside.
  const Ray edge(Vec3f(4, 3.5f, 3.5f), Vec3f(-1, 0, 0));
  cells = check_walk(kUnitGrid, edge, walk(kUnitGrid, edge));
  ASSERT_EQ(cells.size(), 4u);
  EXPECT_EQ(cells[0], kUnitGrid.index(3, 3, 3));
}

TEST(Dda, RaysMissingThePointingAwayOrOutsideTheWindow) {
  EXPECT_TRUE(walk(kUnitGrid, Ray(Vec3f(-1, 5, 2), Vec3f(1, 0, 0))).empty());       // beside the grid
  EXPECT_TRUE(walk(kUnitGrid, Ray(Vec3f(-1, 2, 2), Vec3f(-1, 0, 0))).empty());      // pointing away
  EXPECT_TRUE(walk(kUnitGrid, Ray(Vec3f(-1, 2, 2), Vec3f(1, 0, 0), 0, 0.5f)).empty());  // tmax before entry
  EXPECT_TRUE(walk(kUnitGrid, Ray(Vec3f(-1, 2, 2), Vec3f(1, 0, 0), 6, kInf)).empty());  // tmin after exit
  EXPECT_TRUE(walk(kUnitGrid, Ray(Vec3f(-1, -1, 2), Vec3f(1, 0.01f, 0))).empty());  // passes below
}

TEST(Dda, TminTmaxWindowLimitsTheCells) {
  const Ray r(Vec3f(-1, 0.5f, 0.5f), Vec3f(1, 0, 0), 2.5f, 3.5f);  // x in [1.5, 2.5]
  const auto v = walk(kUnitGrid, r);
  const auto cells = check_walk(kUnitGrid, r, v);
  ASSERT_EQ(cells.size(), 2u);
  EXPECT_EQ(cells[0], kUnitGrid.index(1, 0, 0));
  EXPECT_EQ(cells[1], kUnitGrid.index(2, 0, 0));
  EXPECT_DOUBLE_EQ(v.front().t_enter, 2.5);
  EXPECT_DOUBLE_EQ(v.back().t_exit, 3.5);
  // Starting inside the grid (tmin = 0 inside): the first cell is the origin's.
  const Ray in(Vec3f(2.5f, 1.5f, 0.5f), Vec3f(-1, 1, 0));
  const auto ci = check_walk(kUnitGrid, in, walk(kUnitGrid, in));
  ASSERT_FALSE(ci.empty());
  EXPECT_EQ(ci.front(), kUnitGrid.index(2, 1, 0));
}

TEST(Dda, RandomRaysVisitEveryCellTheyCross) {
  const DdaGrid g = make_dda_grid(Vec3d(-1, 0, 2), Vec3d(2, 1, 2.5), GridRes{13, 7, 5});
  Pcg32 rng(21, 3);
  for (int i = 0; i < 2000; ++i) {
    const Vec3f org(-2 + 5 * rng.uniform(), -1 + 3 * rng.uniform(), 1.5f + 1.5f * rng.uniform());
    Vec3f dir = test::random_direction(rng);
    if (i % 5 == 0) dir[i % 3] = (i % 2) ? 0.0f : -0.0f;
    if (dir.squaredNorm() == 0) continue;
    const Ray r(org, dir);
    const auto v = walk(g, r);
    const auto cells = check_walk(g, r, v);
    // Reference: sample the segment densely; every sampled point's cell must
    // be among the visited ones.
    const DdaRay dr(r);
    double t0 = r.tmin, t1 = r.tmax;
    if (!dda_clip(dr, g.lo, g.hi, t0, t1)) {
      EXPECT_TRUE(v.empty());
      continue;
    }
    const std::set<int64_t> visited(cells.begin(), cells.end());
    for (int k = 1; k < 200; ++k) {
      const double t = t0 + (t1 - t0) * k / 200.0;
      int c[3];
      bool on_boundary = false;
      for (int a = 0; a < 3; ++a) {
        const double p = dr.org[a] + t * dr.dir[a];
        const double f = (p - g.lo[a]) * g.inv_cell[a];
        on_boundary |= std::fabs(f - std::round(f)) < 1e-9;
        c[a] = g.coord(a, p);
      }
      if (on_boundary) continue;
      EXPECT_TRUE(visited.count(g.index(c[0], c[1], c[2]))) << "ray " << i << " sample " << k;
    }
  }
}

TEST(Dda, ClearanceIsTheChessboardDistanceToTheNearestOccupiedCell) {
  const DdaGrid g = make_dda_grid(Vec3d(0, 0, 0), Vec3d(1, 1, 1), GridRes{17, 9, 12});
  Pcg32 rng(4, 9);
  std::vector<uint8_t> occupied(g.cells());
  for (auto& o : occupied) o = rng.uniform() < 0.01f;
  const std::vector<uint8_t> d = cell_clearance(g, [&](int64_t c) { return occupied[c] != 0; });
  ASSERT_EQ(d.size(), g.cells());
  for (int64_t c = 0; c < static_cast<int64_t>(g.cells()); ++c) {
    const auto [x, y, z] = coords(g, c);
    int best = kMaxClearance;
    for (int64_t o = 0; o < static_cast<int64_t>(g.cells()); ++o) {
      if (!occupied[o]) continue;
      const auto [ox, oy, oz] = coords(g, o);
      best = std::min(best, std::max({std::abs(ox - x), std::abs(oy - y), std::abs(oz - z)}));
    }
    ASSERT_EQ(d[c], best) << x << " " << y << " " << z;
  }
  // No occupied cell at all: every cell has the cap.
  const std::vector<uint8_t> none = cell_clearance(g, [](int64_t) { return false; });
  EXPECT_TRUE(std::all_of(none.begin(), none.end(), [](uint8_t v) { return v == kMaxClearance; }));
}

TEST(Dda, SkippingWalkVisitsTheSameOccupiedCellsInOrder) {
  // Sparse occupancy: long empty stretches to jump over, and occupied cells
  // the walk must not jump past.
  const DdaGrid g = make_dda_grid(Vec3d(-1, 0, 2), Vec3d(2, 1, 2.5), GridRes{40, 23, 17});
  Pcg32 rng(8, 1);
  std::vector<uint8_t> occupied(g.cells());
  for (auto& o : occupied) o = rng.uniform() < 0.004f;
  const std::vector<uint8_t> clearance = cell_clearance(g, [&](int64_t c) { return occupied[c] != 0; });
  size_t jumps = 0, plain_visits = 0, skipping_visits = 0;
  for (int i = 0; i < 3000; ++i) {
    // Half from inside the grid's box, half from around it.
    const float s = i % 2 ? 1.0f : 0.0f;
    const Vec3f org(-1 - s + (3 + 2 * s) * rng.uniform(), -s + (1 + 2 * s) * rng.uniform(),
                    2 - s + (0.5f + 2 * s) * rng.uniform());
    Vec3f dir = test::random_direction(rng);
    if (i % 5 == 0) dir[i % 3] = (i % 2) ? 0.0f : -0.0f;
    if (dir.squaredNorm() == 0) continue;
    const Ray r(org, dir);
    const DdaRay dr(r);
    double t0 = r.tmin, t1 = r.tmax;
    if (!dda_clip(dr, g.lo, g.hi, t0, t1)) continue;
    std::vector<Visit> plain, skipping;
    dda_walk(g, dr, t0, t1, [&](int64_t c, double te, double tx) {
      if (occupied[c]) plain.push_back({c, te, tx});
      ++plain_visits;
      return false;
    });
    double last_exit = t0;
    dda_walk_skipping(g, dr, t0, t1, [&](int64_t c) { return clearance[c]; }, [&](int64_t c, double te, double tx) {
      EXPECT_GE(te, last_exit - 1e-12) << "ray " << i;  // never backwards
      jumps += te > last_exit + 1e-12;
      last_exit = tx;
      if (occupied[c]) skipping.push_back({c, te, tx});
      ++skipping_visits;
      return false;
    });
    ASSERT_EQ(plain.size(), skipping.size()) << "ray " << i;
    for (size_t k = 0; k < plain.size(); ++k) {
      EXPECT_EQ(plain[k].cell, skipping[k].cell) << "ray " << i;
      EXPECT_NEAR(plain[k].t_exit, skipping[k].t_exit, 1e-9) << "ray " << i;
    }
  }
  EXPECT_GT(jumps, 1500u);
  EXPECT_LT(skipping_visits, plain_visits / 2);
}

}  // namespace
}  // namespace raylab
