// The grid resolution rule (accel/core/grid/grid_resolution.h): about lambda N
// cubic cells, flat, line and point boxes, the budget, res=AxBxC strings.
#include <gtest/gtest.h>

#include "accel/core/grid/grid_resolution.h"
#include "base/spec.h"

namespace raylab {
namespace {

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

}  // namespace
}  // namespace raylab
