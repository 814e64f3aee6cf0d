// Grids: the resolution rule, the triangle/box overlap test, cell
// assignment, the 3D-DDA's corner cases, and grid / hashgrid / grid2 against
// the brute-force reference on Cornell, soups, a flat scene and a teapot in a
// stadium; memory budget and bad specs (agreement with Embree:
// tests/test_structures_verify.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <tuple>
#include <vector>

#include "accel/grid/cell_clearance.h"
#include "accel/core/grid/cell_overlap.h"
#include "accel/core/grid/dda.h"
#include "accel/core/grid/grid_resolution.h"
#include "accel/grid/hash_grid.h"
#include "accel/core/tri_box_overlap.h"
#include "accel/grid/two_level_grid.h"
#include "accel/grid/uniform_grid.h"
#include "accel/registry.h"
#include "tests/accel_test_util.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

using test::kStadiumObject;

// ---------------------------------------------------------------------------
// Comparing an accelerator with the brute-force reference (same watertight
// test, so answers must agree up to ties within 1e-6 of the distance).

using test::flat_tiles_mesh;
using test::mesh_test_rays;
using test::teapot_in_stadium_mesh;

struct Mismatches {
  size_t closest = 0, occlusion = 0, rays = 0;
};

Mismatches compare_with_brute(const TriangleMesh& mesh, const std::string& spec, const std::vector<Ray>& rays,
                              const test::BruteReference& ref) {
  auto accel = make_accelerator(spec);
  accel->build(mesh);
  const test::Disagreement d = test::compare_with_brute(*accel, ref, rays, spec, 1e-6f);
  return {d.closest, d.occlusion, rays.size()};
}

Mismatches compare_with_brute(const TriangleMesh& mesh, const std::string& spec, const std::vector<Ray>& rays) {
  return compare_with_brute(mesh, spec, rays, test::brute_reference(mesh, rays));
}

const std::vector<std::string> kGridSpecs = {"grid", "hashgrid", "grid2", "grid:assign=bbox", "hashgrid:density=4",
                                             "grid2:top=1,density=2", "grid:res=7x3x5"};

void expect_all_agree(const TriangleMesh& mesh, const std::vector<Ray>& rays, const std::string& what) {
  const test::BruteReference reference = test::brute_reference(mesh, rays);
  for (const auto& spec : kGridSpecs) {
    const Mismatches m = compare_with_brute(mesh, spec, rays, reference);
    EXPECT_EQ(m.closest, 0u) << spec << " on " << what << " (" << m.rays << " rays)";
    EXPECT_EQ(m.occlusion, 0u) << spec << " on " << what;
  }
}

// ---------------------------------------------------------------------------
// Resolution rule

TEST(GridResolution, RuleGivesAboutLambdaNCubicCells) {
  // Cubic cells: V = 8, s = (8 / 8000)^(1/3) = 0.1 -> 40x20x10 = 8000 cells.
  const GridRes r = resolution_by_density(Vec3d(4, 2, 1), 8000, 1.0);
  EXPECT_EQ(r, (GridRes{40, 20, 10}));
  const GridRes r8 = resolution_by_density(Vec3d(4, 2, 1), 8000, 8.0);
  EXPECT_EQ(r8, (GridRes{80, 40, 20}));
  const GridRes small = resolution_by_density(Vec3d(1, 1, 1), 1000, 0.125);
  EXPECT_EQ(small, (GridRes{5, 5, 5}));
}

TEST(GridResolution, FlatLineAndPointBoxesNeverDivideByZero) {
  EXPECT_EQ(resolution_by_density(Vec3d(1, 1, 0), 100, 1.0), (GridRes{10, 10, 1}));
  EXPECT_EQ(resolution_by_density(Vec3d(0, 2, 1), 200, 1.0), (GridRes{1, 20, 10}));
  EXPECT_EQ(resolution_by_density(Vec3d(5, 0, 0), 50, 1.0), (GridRes{50, 1, 1}));
  EXPECT_EQ(resolution_by_density(Vec3d(0, 0, 0), 1000, 1.0), (GridRes{1, 1, 1}));
  EXPECT_EQ(resolution_by_density(Vec3d(1, 1, 1), 0, 1.0), (GridRes{1, 1, 1}));
  // A nearly flat box: the thin side is shorter than a cell and gets one.
  const GridRes thin = resolution_by_density(Vec3d(1, 1, 1e-6), 10000, 1.0);
  EXPECT_EQ(thin, (GridRes{100, 100, 1}));
}

TEST(GridResolution, BudgetLowersLambda) {
  const ChosenResolution c = choose_resolution(Vec3d(1, 1, 1), 1e6, 8.0, 100000);
  EXPECT_TRUE(c.capped);
  EXPECT_LE(total_cells(c.res), 100000u);
  EXPECT_GT(total_cells(c.res), 50000u);  // lowered to about the budget, not far below
  EXPECT_LT(c.lambda, 8.0);
  const ChosenResolution free = choose_resolution(Vec3d(1, 1, 1), 1000, 1.0, 1u << 20);
  EXPECT_FALSE(free.capped);
  EXPECT_EQ(free.lambda, 1.0);
  const ChosenResolution r = cap_resolution(GridRes{1000, 1000, 1000}, 1000000);
  EXPECT_TRUE(r.capped);
  EXPECT_LE(total_cells(r.res), 1000000u);
  EXPECT_GE(total_cells(r.res), 500000u);
}

TEST(GridResolution, ParsesAndRejectsResolutionStrings) {
  EXPECT_EQ(parse_grid_resolution("64x64x32"), (GridRes{64, 64, 32}));
  EXPECT_EQ(parse_grid_resolution("1X2x3"), (GridRes{1, 2, 3}));
  for (const char* bad : {"64x64", "0x1x1", "axbxc", "64x64x32x2", "-1x2x3", "2000000x1x1", "", "4x4x", "4 x4x4"})
    EXPECT_THROW(parse_grid_resolution(bad), SpecError) << bad;
}

// ---------------------------------------------------------------------------
// Triangle/box overlap and cell assignment

TEST(TriangleBoxOverlap, SeparatingAxisCases) {
  const Vec3d lo(0, 0, 0), hi(1, 1, 1);
  // All vertices outside, the triangle slices through the box.
  EXPECT_TRUE(triangle_box_overlap(lo, hi, {-5, -5, 0.5}, {5, -5, 0.5}, {0, 5, 0.5}));
  // Touching a face counts as overlap.
  EXPECT_TRUE(triangle_box_overlap(lo, hi, {1, 0.2, 0.2}, {2, 0.2, 0.8}, {1, 0.8, 0.5}));
  // Separated along a box normal (the bounds do not overlap in x).
  EXPECT_FALSE(triangle_box_overlap(lo, hi, {1.4, 1.4, -1}, {1.4, 1.4, 3}, {3, -1, 1}));
  // Bounds overlap, but the plane x+y+z = 3.1 passes beyond the corner (1,1,1).
  EXPECT_FALSE(triangle_box_overlap(lo, hi, {3.1, 0, 0}, {0, 3.1, 0}, {0, 0, 3.1}));
  // The plane x+y+z = 2.5 cuts off the corner and the triangle contains (5/6, 5/6, 5/6).
  EXPECT_TRUE(triangle_box_overlap(lo, hi, {2.5, 0, 0}, {0, 2.5, 0}, {0, 0, 2.5}));
  // Edge-axis separation: bounds overlap and the plane z = 0.5 cuts the box,
  // but the triangle lies beyond x + y = 3.3; only the axis edge x z-normal
  // (proportional to (1, 1, 0)) separates it.
  EXPECT_FALSE(triangle_box_overlap(lo, hi, {0.8, 2.5, 0.5}, {2.5, 0.8, 0.5}, {2.5, 2.5, 0.5}));
  // The same triangle moved until its hypotenuse passes through the box.
  EXPECT_TRUE(triangle_box_overlap(lo, hi, {0.2, 1.6, 0.5}, {1.6, 0.2, 0.5}, {2.5, 2.5, 0.5}));
  // A degenerate triangle (segment) through the box, and a point outside.
  EXPECT_TRUE(triangle_box_overlap(lo, hi, {-1, 0.5, 0.5}, {2, 0.5, 0.5}, {0.5, 0.5, 0.5}));
  EXPECT_FALSE(triangle_box_overlap(lo, hi, {2, 2, 2}, {2, 2, 2}, {2, 2, 2}));
}

// Reference: clip the triangle polygon against the box's six planes
// (Sutherland-Hodgman); the triangle overlaps when something is left.
bool clip_overlap(const Vec3d& lo, const Vec3d& hi, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  std::vector<Vec3d> poly = {a, b, c};
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      std::vector<Vec3d> out;
      auto inside = [&](const Vec3d& p) { return side == 0 ? p[axis] >= lo[axis] : p[axis] <= hi[axis]; };
      const double plane = side == 0 ? lo[axis] : hi[axis];
      for (size_t i = 0; i < poly.size(); ++i) {
        const Vec3d& p = poly[i];
        const Vec3d& q = poly[(i + 1) % poly.size()];
        if (inside(p)) out.push_back(p);
        if (inside(p) != inside(q)) {
          const double t = (plane - p[axis]) / (q[axis] - p[axis]);
          Vec3d x = p + t * (q - p);
          x[axis] = plane;
          out.push_back(x);
        }
      }
      poly = std::move(out);
      if (poly.empty()) return false;
    }
  return true;
}

TEST(TriangleBoxOverlap, AgreesWithPolygonClippingOnRandomTriangles) {
  Pcg32 rng(3, 7);
  const Vec3d lo(0, 0, 0), hi(1, 1, 1);
  size_t overlaps = 0, checked = 0;
  for (int i = 0; i < 20000; ++i) {
    Vec3d v[3];
    const Vec3d c(3 * rng.uniform() - 1, 3 * rng.uniform() - 1, 3 * rng.uniform() - 1);
    for (auto& p : v) p = c + Vec3d(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * 2.0;
    const bool sat = triangle_box_overlap(lo, hi, v[0], v[1], v[2]);
    // Decided cases only: the answer must not change under a tiny shrink/grow.
    const double e = 1e-9;
    const bool grown = clip_overlap(lo.array() - e, hi.array() + e, v[0], v[1], v[2]);
    const bool shrunk = clip_overlap(lo.array() + e, hi.array() - e, v[0], v[1], v[2]);
    if (grown != shrunk) continue;
    ++checked;
    overlaps += sat;
    EXPECT_EQ(sat, grown) << "triangle " << i;
  }
  EXPECT_GT(checked, 19000u);
  EXPECT_GT(overlaps, 2000u);  // both outcomes are exercised
  EXPECT_LT(overlaps, checked - 2000u);
}

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

// ---------------------------------------------------------------------------
// 3D-DDA on its own

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

// ---------------------------------------------------------------------------
// Accelerators against brute force

TEST(GridAccel, CornellBoxAgreesWithBrute) {
  const test::NamedMesh s{"cornell", cornell_box_mesh()};
  expect_all_agree(s.mesh, mesh_test_rays(s.mesh, 4000, 1), "cornell");
}

TEST(GridAccel, RandomSoupsAgreeWithBrute) {
  for (const auto& [n, size, seed] : {std::tuple{2000, 1.0f, 1}, std::tuple{5000, 4.0f, 2}, std::tuple{300, 20.0f, 3}}) {
    const test::NamedMesh s = test::soup(n, seed, size);
    expect_all_agree(s.mesh, mesh_test_rays(s.mesh, 3000, seed), s.name);
  }
}

TEST(GridAccel, AxisAlignedFlatSceneAgreesWithBrute) {
  const TriangleMesh m = flat_tiles_mesh(16, 400, 4);
  std::vector<Ray> rays = mesh_test_rays(m, 3000, 5);
  // Rays parallel to the plane, in it, and through it along +-z exactly.
  Pcg32 rng(6, 2);
  for (int i = 0; i < 500; ++i) {
    const float x = rng.uniform(), y = rng.uniform();
    rays.emplace_back(Vec3f(x, y, 2.0f), Vec3f(0.0f, -0.0f, -1.0f));
    rays.emplace_back(Vec3f(x, y, -1.0f), Vec3f(-0.0f, 0.0f, 1.0f));
    rays.emplace_back(Vec3f(-1, y, 0.5f), Vec3f(1, 0, 0));           // in the plane
    rays.emplace_back(Vec3f(x, y, 0.6f), Vec3f(1, rng.uniform(), 0));  // parallel above
  }
  expect_all_agree(m, rays, "flat scene");
  // And the plane is really hit from both sides.
  auto g = make_accelerator("grid");
  g->build(m);
  const Hit h = g->intersect1(Ray(Vec3f(0.3f, 0.3f, 2.0f), Vec3f(0, 0, -1)));
  ASSERT_TRUE(h.valid());
  EXPECT_FLOAT_EQ(h.t, 1.5f);
}

TEST(GridAccel, TeapotInAStadiumAgreesWithBrute) {
  const TriangleMesh m = teapot_in_stadium_mesh();
  std::vector<Ray> rays = mesh_test_rays(m, 2000, 7);
  // Rays from around the room aimed at the small dense object.
  Pcg32 rng(8, 4);
  for (int i = 0; i < 2000; ++i) {
    const Vec3f org(800 * rng.uniform() - 400, 800 * rng.uniform() - 400, 800 * rng.uniform() - 400);
    const Vec3f target = kStadiumObject + 0.6f * test::random_direction(rng);
    rays.emplace_back(org, (target - org).normalized());
  }
  const test::BruteReference reference = test::brute_reference(m, rays);
  for (const auto& spec : {"grid", "hashgrid", "grid2", "grid2:top=0.01"}) {
    const Mismatches mm = compare_with_brute(m, spec, rays, reference);
    EXPECT_EQ(mm.closest, 0u) << spec;
    EXPECT_EQ(mm.occlusion, 0u) << spec;
  }
}

TEST(GridAccel, TwoLevelGridStaysUsableInTheStadium) {
  // Counted work, not time: rays aimed at the dense object test far fewer
  // triangles in grid2, whose sub-grid adapts to the object.
  const TriangleMesh m = teapot_in_stadium_mesh();
  std::vector<Ray> rays;
  Pcg32 rng(9, 4);
  for (int i = 0; i < 2000; ++i) {
    const Vec3f org = kStadiumObject + Vec3f(0, 0, 0) + 20.0f * test::random_direction(rng);
    const Vec3f target = kStadiumObject + 0.5f * test::random_direction(rng);
    rays.emplace_back(org, (target - org).normalized());
  }
  auto tests_per_ray = [&](const std::string& spec) {
    const test::CountedHits traced = test::counted_hits(spec, m, rays);
    size_t hit_count = 0;
    for (const Hit& h : traced.hits) hit_count += h.valid();
    EXPECT_EQ(hit_count, rays.size()) << spec;  // every ray hits the object or the room
    return static_cast<double>(traced.stats.triangle_tests) / static_cast<double>(traced.stats.rays);
  };
  const double grid = tests_per_ray("grid");
  const double grid2 = tests_per_ray("grid2");
  auto two = make_accelerator("grid2");
  const BuildStats st = two->build(m);
  EXPECT_GT(st.extra.at("large_refs"), 0.0);  // the walls and the table top stay at the top level
  EXPECT_GT(st.extra.at("subgrids"), 0.0);
  EXPECT_GT(grid, 500.0);           // the single grid collapses: the object sits in a few cells
  EXPECT_LT(grid2 * 10.0, grid);    // the two-level grid does not
  EXPECT_LT(grid2, 50.0);
}

TEST(GridAccel, MeshFarFromTheOriginCostsWhatItCostsAtTheOrigin) {  // and the wide BVH
  // A cell margin sized from the absolute coordinates would give a sphere
  // of radius 8 at 3e5 a margin (0.6) as large as a cell, and every cell
  // would list its neighbours' triangles. Counted work, not time:
  // the same rays (moved with the mesh) visit about as many cells and test
  // about as many triangles far away as at the origin, and all hit.
  const Vec3f offset(3e5f, 1e5f, -2e5f);
  const float radius = 8.0f;
  const TriangleMesh near_mesh = make_uv_sphere(96, 48, Vec3f::Zero(), radius);
  const TriangleMesh far_mesh = make_uv_sphere(96, 48, offset, radius);
  std::vector<Ray> near_rays, far_rays;
  Pcg32 rng(17, 3);
  for (int i = 0; i < 600; ++i) {
    // From inside towards the shell, and from outside at the sphere.
    const Vec3f org = (i % 2 ? 0.5f : 2.5f) * radius * test::random_direction(rng);
    const Vec3f target = 0.5f * radius * test::random_direction(rng);
    const Vec3f dir = i % 2 ? test::random_direction(rng) : Vec3f((target - org).normalized());
    near_rays.emplace_back(org, dir);
    far_rays.emplace_back(Vec3f(org + offset), dir);
  }
  auto work = [](const std::string& spec, const TriangleMesh& m, const std::vector<Ray>& rays) {
    auto a = make_accelerator(spec);
    a->build(m);
    std::vector<Hit> hits(rays.size());
    TraversalStats st;
    a->intersect(rays, hits, &st);
    size_t hit_count = 0;
    for (const Hit& h : hits) hit_count += h.valid();
    EXPECT_EQ(hit_count, rays.size()) << spec;  // every ray meets the closed sphere
    return std::pair<double, double>(static_cast<double>(st.nodes_visited) / static_cast<double>(rays.size()),
                                     static_cast<double>(st.triangle_tests) / static_cast<double>(rays.size()));
  };
  for (const std::string spec : {"grid", "hashgrid", "grid2"}) {
    const auto [near_cells, near_tests] = work(spec, near_mesh, near_rays);
    const auto [far_cells, far_tests] = work(spec, far_mesh, far_rays);
    EXPECT_LT(far_cells, 1.25 * near_cells) << spec;
    EXPECT_GT(far_cells, 0.8 * near_cells) << spec;
    EXPECT_LT(far_tests, 1.5 * near_tests) << spec;  // the old margin: 5-11x
  }
  // The wide BVH's FMA box test is exact only to 2^-22 |origin| (0.07 at 3e5):
  // on a radius-1 sphere there every ray entered the boxes of its neighbours
  // too (40x the triangle tests) until such rays took the exact kernel.
  const TriangleMesh near_small = make_uv_sphere(128, 64, Vec3f::Zero(), 1.0f);
  const TriangleMesh far_small = make_uv_sphere(128, 64, offset, 1.0f);
  std::vector<Ray> near_small_rays, far_small_rays;
  for (const Ray& r : near_rays) {
    near_small_rays.emplace_back(Vec3f(r.org / radius), r.dir);
    far_small_rays.emplace_back(Vec3f(r.org / radius + offset), r.dir);
  }
  for (const std::string spec : {"bvh", "bvh:layout=bvh4", "bvh:packet=16"}) {
    const auto [near_nodes, near_tests] = work(spec, near_small, near_small_rays);
    const auto [far_nodes, far_tests] = work(spec, far_small, far_small_rays);
    EXPECT_LT(far_nodes, 1.5 * near_nodes) << spec;
    EXPECT_LT(far_tests, 1.5 * near_tests) << spec;
  }
}

TEST(GridAccel, HitFarAlongASpanningTriangleWaitsForNearerCells) {
  // T is nearly parallel to the ray and listed in every cell the ray walks;
  // its hit at x = 9 is found in the first cell and must not be accepted
  // there: the small triangle S at x = 5 is nearer.
  TriangleMesh m;
  append_triangle(m, {0, 0, 0.59f}, {0, 1, 0.59f}, {10, 0.5f, 0.49f});  // T, id 0
  append_triangle(m, {5, 0.3f, 0.3f}, {5, 0.7f, 0.3f}, {5, 0.5f, 0.7f});  // S, id 1
  append_triangle(m, {0, 0, 0}, {10, 0, 0}, {10, 1, 1});                 // grows the box, id 2
  const Ray r(Vec3f(-0.5f, 0.5f, 0.5f), Vec3f(1, 0, 0));
  for (const auto& spec : {"grid:res=10x1x1", "hashgrid:res=10x1x1", "grid2:top=1,density=1", "grid", "grid:res=40x3x3"}) {
    auto a = make_accelerator(spec);
    a->build(m);
    const Hit h = a->intersect1(r);
    ASSERT_TRUE(h.valid()) << spec;
    EXPECT_EQ(h.prim, 1u) << spec;
    EXPECT_FLOAT_EQ(h.t, 5.5f) << spec;
    // Without S the far hit on T is found (the mailbox must not lose it).
    TriangleMesh m2 = m;
    m2.triangles.erase(m2.triangles.begin() + 1);
    auto b = make_accelerator(spec);
    b->build(m2);
    const Hit h2 = b->intersect1(r);
    ASSERT_TRUE(h2.valid()) << spec;
    EXPECT_EQ(h2.prim, 0u) << spec;
    EXPECT_NEAR(h2.t, 9.5f, 1e-4f) << spec;
  }
}

TEST(GridAccel, TminTmaxWindowsAndStartingInside) {
  TriangleMesh m;
  for (int i = 0; i < 5; ++i) {
    const float x = 1.0f + i;
    append_triangle(m, {x, -1, -1}, {x, 3, -1}, {x, -1, 3});  // planes x = 1..5 covering y,z in [0,1]
  }
  for (const auto& spec : {"grid", "hashgrid", "grid2", "grid:res=3x2x2"}) {
    auto a = make_accelerator(spec);
    a->build(m);
    const Vec3f dir(1, 0, 0);
    const Vec3f org(0, 0.25f, 0.25f);
    EXPECT_EQ(a->intersect1(Ray(org, dir)).prim, 0u) << spec;
    EXPECT_EQ(a->intersect1(Ray(org, dir, 1.5f)).prim, 1u) << spec;          // tmin skips x = 1
    EXPECT_EQ(a->intersect1(Ray(org, dir, 2.0f)).prim, 1u) << spec;          // tmin exactly at x = 2
    EXPECT_FALSE(a->intersect1(Ray(org, dir, 0.0f, 0.99f)).valid()) << spec;  // tmax before x = 1
    EXPECT_EQ(a->intersect1(Ray(org, dir, 0.0f, 1.0f)).prim, 0u) << spec;    // tmax exactly at x = 1
    EXPECT_FALSE(a->intersect1(Ray(org, dir, 5.5f)).valid()) << spec;
    EXPECT_EQ(a->intersect1(Ray(Vec3f(3.5f, 0.5f, 0.5f), -dir)).prim, 2u) << spec;  // from inside, backwards
    EXPECT_EQ(a->intersect1(Ray(Vec3f(3.0f, 0.5f, 0.5f), dir)).prim, 2u) << spec;  // on a triangle: t = 0 hit
    EXPECT_TRUE(a->occluded1(Ray(org, dir, 3.5f, 4.5f))) << spec;
    EXPECT_FALSE(a->occluded1(Ray(org, dir, 3.2f, 3.8f))) << spec;
    // Missing the grid, pointing away, invalid rays.
    EXPECT_FALSE(a->intersect1(Ray(Vec3f(0, 10, 0), dir)).valid()) << spec;
    EXPECT_FALSE(a->intersect1(Ray(org, -dir)).valid()) << spec;
    EXPECT_FALSE(a->intersect1(Ray(org, Vec3f::Zero())).valid()) << spec;
    EXPECT_FALSE(a->intersect1(Ray(org, dir, 2.0f, 1.0f)).valid()) << spec;
    EXPECT_FALSE(a->intersect1(Ray(Vec3f(NAN, 0, 0), dir)).valid()) << spec;
    EXPECT_FALSE(a->occluded1(Ray(org, Vec3f::Zero()))) << spec;
  }
}

TEST(GridAccel, OriginsOnCellBoundariesAndRaysAlongThem) {
  // Origins placed exactly on the grid's cell boundaries (as floats), rays
  // along and across them, compared with brute force.
  const test::NamedMesh s = test::soup(3000, 11, 2.0f);
  GridOptions opt;
  opt.res = GridRes{8, 8, 8};
  BuildStats st;
  const UniformGrid g = build_uniform_grid(s.mesh, opt, st);
  std::vector<Ray> rays;
  Pcg32 rng(12, 9);
  for (int i = 0; i < 3000; ++i) {
    Vec3f org;
    for (int a = 0; a < 3; ++a) org[a] = static_cast<float>(g.dda.boundary(a, static_cast<int64_t>(rng.next() % 9)));
    Vec3f dir = test::random_direction(rng);
    const int zeroed = static_cast<int>(rng.next() % 4);
    if (zeroed < 3) dir[zeroed] = (i % 2) ? 0.0f : -0.0f;
    if (i % 7 == 0) dir = Vec3f::Unit(i % 3) * ((i % 2) ? 1.0f : -1.0f);
    rays.emplace_back(org, dir);
  }
  const test::BruteReference reference = test::brute_reference(s.mesh, rays);
  for (const auto& spec : {"grid:res=8x8x8", "hashgrid:res=8x8x8", "grid", "grid2"}) {
    const Mismatches m = compare_with_brute(s.mesh, spec, rays, reference);
    EXPECT_EQ(m.closest, 0u) << spec;
    EXPECT_EQ(m.occlusion, 0u) << spec;
  }
}

TEST(GridAccel, DegenerateInputs) {
  // Empty mesh: builds, every ray misses.
  TriangleMesh empty;
  // 1000 copies of one triangle, and degenerate (zero-area) triangles.
  TriangleMesh copies;
  for (int i = 0; i < 1000; ++i) append_triangle(copies, {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  append_triangle(copies, {0, 0, 1}, {1, 1, 1}, {2, 2, 1});  // collinear
  append_triangle(copies, {3, 3, 3}, {3, 3, 3}, {3, 3, 3});  // a point
  for (const auto& spec : {"grid", "hashgrid", "grid2", "grid:assign=bbox"}) {
    auto a = make_accelerator(spec);
    a->build(empty);
    EXPECT_FALSE(a->intersect1(Ray(Vec3f::Zero(), Vec3f::UnitX())).valid());
    EXPECT_FALSE(a->occluded1(Ray(Vec3f::Zero(), Vec3f::UnitX())));
    auto b = make_accelerator(spec);
    const BuildStats st = b->build(copies);
    EXPECT_GE(st.nodes, 1u);
    const Hit h = b->intersect1(Ray(Vec3f(0.2f, 0.2f, 5), Vec3f(0, 0, -1)));
    ASSERT_TRUE(h.valid()) << spec;
    EXPECT_FLOAT_EQ(h.t, 5.0f);
    EXPECT_LT(h.prim, 1000u);
  }
  expect_all_agree(copies, mesh_test_rays(copies, 500, 13), "copies");
}

// ---------------------------------------------------------------------------
// Statistics, memory, budget, parameters

TEST(GridStats, BuildAndTraversalFiguresAreConsistent) {
  const test::NamedMesh s = test::soup(4000, 3, 1.0f);
  for (const auto& spec : {"grid", "hashgrid", "grid2"}) {
    auto a = make_accelerator(spec);
    const BuildStats st = a->build(s.mesh);
    EXPECT_GT(st.bytes, s.mesh.num_triangles() * sizeof(LeafTriangle)) << spec;
    EXPECT_GT(st.nodes, 0u);
    EXPECT_GT(st.leaves, 0u);
    EXPECT_LE(st.leaves, st.nodes);
    for (const char* key : {"empty_fraction", "refs_per_triangle", "mean_tris_per_nonempty_cell", "max_tris_per_cell"})
      ASSERT_TRUE(st.extra.count(key)) << spec << " " << key;
    EXPECT_GE(st.extra.at("refs_per_triangle"), 1.0) << spec;
    EXPECT_GE(st.extra.at("empty_fraction"), 0.0);
    EXPECT_LT(st.extra.at("empty_fraction"), 1.0);
    EXPECT_GE(st.extra.at("max_tris_per_cell"), st.extra.at("mean_tris_per_nonempty_cell"));
    const std::vector<Ray> rays = mesh_test_rays(s.mesh, 1000, 2);
    std::vector<Hit> hits(rays.size());
    TraversalStats ts;
    a->intersect(rays, hits, &ts);
    EXPECT_EQ(ts.rays, rays.size());
    EXPECT_GT(ts.nodes_visited, rays.size() / 2) << spec;
    EXPECT_GT(ts.triangle_tests, 0u);
    EXPECT_LT(ts.triangle_tests, rays.size() * s.mesh.num_triangles() / 20) << spec;  // far below brute force
    // The uninstrumented kernel gives the same answers.
    std::vector<Hit> plain(rays.size());
    a->intersect(rays, plain);
    for (size_t i = 0; i < rays.size(); ++i) EXPECT_EQ(plain[i].prim, hits[i].prim);
  }
  // Dense grid: cells = resolution product, bbox assignment adds references.
  auto exact = make_accelerator("grid:res=10x12x14");
  auto bbox = make_accelerator("grid:res=10x12x14,assign=bbox");
  const BuildStats se = exact->build(s.mesh), sb = bbox->build(s.mesh);
  EXPECT_EQ(se.nodes, 10u * 12u * 14u);
  EXPECT_EQ(se.extra.at("res_y"), 12.0);
  EXPECT_GT(sb.extra.at("refs_per_triangle"), se.extra.at("refs_per_triangle"));
  EXPECT_EQ(se.max_depth, 1);
  auto two = make_accelerator("grid2");
  EXPECT_EQ(two->build(s.mesh).max_depth, 2);
}

TEST(GridMemory, HashGridBytesFollowOccupiedCellsDenseGridBytesFollowResolution) {
  // Teapot in a stadium: at high density almost every dense cell is empty.
  const TriangleMesh m = teapot_in_stadium_mesh();
  struct Figures {
    double bytes, cells, occupied, refs;
  };
  auto figures = [&](const std::string& spec) {
    auto a = make_accelerator(spec);
    const BuildStats st = a->build(m);
    return Figures{static_cast<double>(st.bytes - m.num_triangles() * sizeof(LeafTriangle)), st.extra.at("cells"),
                   st.extra.at("nonempty_cells"), st.extra.at("refs")};
  };
  std::vector<Figures> dense, hashed;
  for (const char* density : {"1", "8", "64", "512"}) {
    // The scalar layout (simd=0): ids into one copy of each triangle.
    dense.push_back(figures(std::string("grid:simd=0,skip=0,density=") + density));
    hashed.push_back(figures(std::string("hashgrid:simd=0,density=") + density));
    const Figures& d = dense.back();
    const Figures& h = hashed.back();
    EXPECT_EQ(d.cells, h.cells) << density;
    EXPECT_EQ(d.occupied, h.occupied) << density;
    EXPECT_EQ(d.refs, h.refs) << density;
    // Dense: 4 bytes per cell and per reference. Hashed: 32 bytes per
    // occupied cell (16-byte slots, load factor 1/2) and 4 per reference.
    EXPECT_EQ(d.bytes, 4.0 * (d.cells + 1) + 4.0 * d.refs + sizeof(UniformGrid)) << density;
    EXPECT_EQ(h.bytes, 32.0 * h.occupied + 4.0 * h.refs + sizeof(HashGrid)) << density;
    // Empty-space skipping (the default): one more byte per cell.
    EXPECT_EQ(figures(std::string("grid:simd=0,density=") + density).bytes, d.bytes + d.cells) << density;
  }
  // From density 1 to 512 the dense grid grows with its cells (512x), the
  // hashed grid with its occupied cells (~70x here: the room's walls).
  EXPECT_GT(dense[3].bytes / dense[0].bytes, 150.0);
  EXPECT_LT(hashed[3].bytes / hashed[0].bytes, 100.0);
  EXPECT_LT(hashed[3].occupied, 0.05 * hashed[3].cells);
  EXPECT_LT(hashed[3].bytes, 0.5 * dense[3].bytes);
  // SIMD blocks (the default): each cell's list as ceil(n / 4) 160-byte
  // blocks in place of its ids, and no triangle copies.
  for (const char* spec : {"grid", "hashgrid", "grid2"}) {
    auto ids = make_accelerator(std::string(spec) + ":simd=0");
    auto blocks = make_accelerator(spec);
    const BuildStats si = ids->build(m), sb = blocks->build(m);
    const double cell_blocks = sb.extra.at("cell_blocks");
    EXPECT_EQ(si.extra.at("cell_blocks"), 0.0) << spec;
    EXPECT_GE(cell_blocks, sb.extra.at("refs") / 4.0) << spec;
    // At most 3 padding lanes per run: the non-empty cells, and grid2's top cells' large lists.
    const double runs = sb.extra.at("nonempty_cells") + (sb.extra.count("top_cells") ? sb.extra.at("top_cells") : 0.0);
    EXPECT_LE(cell_blocks, (sb.extra.at("refs") + 3.0 * runs) / 4.0) << spec;
    EXPECT_EQ(static_cast<double>(sb.bytes),
              static_cast<double>(si.bytes) - 4.0 * sb.extra.at("refs") - m.num_triangles() * sizeof(LeafTriangle) +
                  cell_blocks * sizeof(KdTriangleBlock))
        << spec;
  }
}

TEST(GridBudget, ExceedingTheBudgetLowersDensityWithAWarning) {
  const test::NamedMesh s = test::soup(20000, 5, 1.0f);
  // simd=0: ids (4 bytes per reference); the default SIMD blocks take at
  // least 40 bytes per reference, so their budgets are larger.
  for (const auto& spec : {"grid:simd=0,density=64,budget=0.5", "hashgrid:simd=0,density=64,budget=0.5",
                           "grid2:simd=0,density=64,budget=0.5", "grid:simd=0,res=1000x1000x1000,budget=1",
                           "grid:density=64,budget=4", "hashgrid:density=64,budget=4", "grid2:density=64,budget=4",
                           "grid:res=1000x1000x1000,budget=8"}) {
    auto a = make_accelerator(spec);
    testing::internal::CaptureStderr();
    const BuildStats st = a->build(s.mesh);
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("warning"), std::string::npos) << spec;
    EXPECT_NE(err.find("budget"), std::string::npos) << spec;
    EXPECT_EQ(st.extra.at("budget_capped"), 1.0) << spec;
    const double budget = std::stod(std::string(spec).substr(std::string(spec).find("budget=") + 7));
    EXPECT_LE(static_cast<double>(st.bytes - s.mesh.num_triangles() * sizeof(LeafTriangle)),
              budget * 1024 * 1024 * 1.05)
        << spec;
    if (std::string(spec).find("res=") == std::string::npos) {
      EXPECT_LT(st.extra.at("lambda"), 64.0) << spec;
    }
    // Still correct.
    const Mismatches m = compare_with_brute(s.mesh, spec, mesh_test_rays(s.mesh, 300, 3));
    EXPECT_EQ(m.closest, 0u) << spec;
  }
  // Within the budget: no warning.
  auto ok = make_accelerator("grid");
  testing::internal::CaptureStderr();
  const BuildStats st = ok->build(s.mesh);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  EXPECT_EQ(st.extra.at("budget_capped"), 0.0);
  // A budget that cannot even hold one reference per triangle: a clear error.
  for (const auto& spec : {"grid:budget=0.01", "hashgrid:budget=0.01", "grid2:budget=0.01"}) {
    auto tiny = make_accelerator(spec);
    testing::internal::CaptureStderr();
    EXPECT_THROW(tiny->build(s.mesh), std::runtime_error) << spec;
    testing::internal::GetCapturedStderr();
  }
}

TEST(GridParams, BadParametersAreRejected) {
  for (const char* spec : {"grid:density=0", "grid:density=-1", "grid:density=nan", "grid:density=abc",
                           "grid:density=1e9", "grid:res=0x1x1", "grid:res=64x64", "grid:res=axbxc", "grid:budget=0",
                           "grid:budget=-5", "grid:assign=foo", "grid:tri=fast", "grid:top=1", "hashgrid:res=1x1",
                           "hashgrid:density=0", "grid2:top=0", "grid2:density=-2", "grid2:res=4x4x4",
                           "grid2:assign=none"}) {
    EXPECT_THROW(make_accelerator(spec), SpecError) << spec;
  }
  EXPECT_NO_THROW(make_accelerator("grid:density=0.125,res=4x4x4,budget=16,assign=bbox,tri=mt"));
  EXPECT_NO_THROW(make_accelerator("grid2:top=0.5,density=2"));
}

}  // namespace
}  // namespace raylab
