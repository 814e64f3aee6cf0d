#pragma once
// The exact SAH split of a small node: for at most kSmallSweepMax build
// references, every object split of every axis (the references sorted by
// centroid, each boundary between consecutive ones) is costed, where binning
// would only see a few of them and cost more (build_binned_sah.cpp).
#include <cstdint>

#include "accel/bvh/build_common.h"

namespace raylab::sah {

inline constexpr int kSmallSweepMax = 16;

struct SmallSplit {
  int axis = -1;
  int pos = 0;  // the first pos references of order[axis] go left (1 <= pos < n)
  float cost = 0.0f;  // left half area * pos + right half area * (n - pos)
};

// refs[0, n), 2 <= n <= kSmallSweepMax. Fills order[a] (a = 0, 1, 2) with the
// references' indices sorted by centroid on axis a (stable, any bits, NaN
// included, have a place) and returns the cheapest split. Ties go to the
// most central position, then to the first axis and position; a NaN cost
// (an overflowed extent times a flat one) counts as infinite, so some split
// is always chosen. With AVX-512 the sweep runs in registers; the result is
// choose_small_split_scalar's, bit for bit.
SmallSplit choose_small_split(const BuildRef* refs, int n, uint8_t (&order)[3][kSmallSweepMax]);

// The portable sweep, one position at a time (the definition; tests compare).
SmallSplit choose_small_split_scalar(const BuildRef* refs, int n, uint8_t (&order)[3][kSmallSweepMax]);

}  // namespace raylab::sah
