#pragma once
// Exclusive prefix sum in place, in parallel for long arrays: v[0..n) holds
// counts and becomes offsets, v[n] (the last entry) the total. The grid
// builders turn per-cell and per-triangle counts into list offsets with it.
#include <cstddef>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_scan.h>

namespace raylab {

template <typename T>
void exclusive_scan_counts(std::vector<T>& v, size_t grain = size_t{1} << 14) {
  const size_t n = v.size() - 1;
  if (n < 4 * grain) {  // not worth the threads
    T sum = 0;
    for (size_t i = 0; i < n; ++i) {
      const T c = v[i];
      v[i] = sum;
      sum += c;
    }
    v[n] = sum;
    return;
  }
  v[n] = tbb::parallel_scan(
      tbb::blocked_range<size_t>(0, n, grain), T{0},
      [&](const tbb::blocked_range<size_t>& r, T sum, bool is_final) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
          const T c = v[i];
          if (is_final) v[i] = sum;
          sum += c;
        }
        return sum;
      },
      [](T a, T b) { return a + b; });
}

}  // namespace raylab
