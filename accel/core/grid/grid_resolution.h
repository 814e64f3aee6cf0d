#pragma once
// How many cells a uniform grid gets.
//
// The classic rule (Cleary & Wyvill 1988; the "n^(1/3) rule" of the grid
// literature) asks for about lambda * N cells for N triangles, with cubic
// cells: a cell side s = (V / (lambda N))^(1/3) for a box of volume V, and
// k_i = max(1, round(d_i / s)) cells along a side of length d_i.
//
// Generalised to boxes with flat or thin sides: a side shorter than one cell
// gets a single cell and drops out of the rule, and s is recomputed over the
// remaining m sides as (prod d_i / (lambda N))^(1/m). A box flat in one axis
// therefore gets a 2D rule, a box flat in two axes a 1D rule, and a point a
// single cell; nothing divides by zero.
//
// The caller's memory budget caps the total number of cells: when the rule
// asks for more, lambda is lowered until it fits (reported, never an
// allocation failure).
#include <array>
#include <cstdint>
#include <string>

#include "base/vec.h"

namespace raylab {

using GridRes = std::array<int32_t, 3>;

// Largest number of cells along one axis (keeps linear cell indices and hash
// keys within 64 bits, and cell coordinates exact in double).
inline constexpr int32_t kMaxGridAxisCells = 1 << 20;

inline uint64_t total_cells(const GridRes& r) {
  return static_cast<uint64_t>(r[0]) * static_cast<uint64_t>(r[1]) * static_cast<uint64_t>(r[2]);
}

// Cells per axis by the rule above, for `extent` (side lengths, >= 0),
// `count` primitives and density `lambda` (> 0). Not capped.
GridRes resolution_by_density(const Vec3d& extent, double count, double lambda);

struct ChosenResolution {
  GridRes res{1, 1, 1};
  double lambda = 1.0;        // the density actually used (lowered when capped)
  bool capped = false;        // the budget forced a lower density (or smaller res)
};

// The rule with a cap on the total number of cells: lambda is lowered until
// the resolution fits `max_cells` (>= 1).
ChosenResolution choose_resolution(const Vec3d& extent, double count, double lambda, uint64_t max_cells);

// An explicit resolution, scaled down uniformly when it exceeds `max_cells`.
ChosenResolution cap_resolution(const GridRes& requested, uint64_t max_cells);

// Parses "AxBxC" (positive integers, each at most kMaxGridAxisCells);
// throws SpecError with a message otherwise.
GridRes parse_grid_resolution(const std::string& text);

std::string format_grid_resolution(const GridRes& r);

}  // namespace raylab
