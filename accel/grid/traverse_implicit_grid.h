#pragma once
// The implicit grid's walk: the uniform grid's 3D-DDA and stopping rule
// (grid_ray_query.h); a cell's candidates are the AND of its x, y and z
// slab bit arrays, over the words where all three have bits.
#include <bit>
#include <cstdint>

#include "accel/core/grid/grid_ray_query.h"
#include "accel/grid/implicit_grid.h"

namespace raylab {

struct ImplicitGridView {
  const ImplicitGrid* g = nullptr;
};

inline ImplicitGridView grid_view(const ImplicitGrid& g) { return ImplicitGridView{&g}; }

template <TriangleTest kTest, bool kAnyHit, bool kCount, bool kFarFirst>
inline Hit traverse_grid(const ImplicitGridView& v, const Ray& ray, TraversalStats* stats) {
  // Traced before build(): no grid yet, every ray misses.
  static const ImplicitGrid kUnbuilt;
  const ImplicitGrid& g = v.g ? *v.g : kUnbuilt;
  return walk_grid<kTest, kAnyHit, kCount, false, kFarFirst>(g.dda, g.empty, ray, stats, [&](const DdaRay& dr, double t0, double t1, auto& q) {
    const int64_t sy = g.dda.stride[1], sz = g.dda.stride[2];
    dda_walk(g.dda, dr, t0, t1, [&](int64_t cell, double, double t_exit) {
      const int64_t z = cell / sz, rem = cell - z * sz, y = rem / sy, x = rem - y * sy;
      const size_t s[3] = {g.slab(0, static_cast<int32_t>(x)), g.slab(1, static_cast<int32_t>(y)),
                           g.slab(2, static_cast<int32_t>(z))};
      const uint32_t lo = std::max({g.word_lo[s[0]], g.word_lo[s[1]], g.word_lo[s[2]]});
      const uint32_t hi = std::min({g.word_hi[s[0]], g.word_hi[s[1]], g.word_hi[s[2]]});
      const uint64_t* bx = g.bits.data() + s[0] * g.words;
      const uint64_t* by = g.bits.data() + s[1] * g.words;
      const uint64_t* bz = g.bits.data() + s[2] * g.words;
      if constexpr (kCount) {
        // The cell's triangles: those in all three of its slabs.
        uint64_t in_cell = 0;
        for (uint32_t w = lo; w < hi; ++w) in_cell += static_cast<uint64_t>(std::popcount(bx[w] & by[w] & bz[w]));
        q.rec.count_cell(in_cell);
      }
      for (uint32_t w = lo; w < hi; ++w) {
        uint64_t m = bx[w] & by[w] & bz[w];
        while (m) {
          const uint32_t id = w * 64 + static_cast<uint32_t>(std::countr_zero(m));
          m &= m - 1;
          if (q.mailbox.seen(id)) continue;
          if (intersect_leaf_triangle(q.pre, ray, g.tris[id], q.rec)) {
            if constexpr (kAnyHit) return true;
          }
        }
      }
      if constexpr (kAnyHit) return false;
      return q.done_at(t_exit);
    });
  });
}

}  // namespace raylab
