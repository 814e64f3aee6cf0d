#pragma once
// Hierarchical grid walk (hgrid.h): every occupied level's box is clipped
// against the ray; the levels are walked in order of their entry distance,
// each with the 3D-DDA of the uniform grid (accel/grid/dda.h) under the
// grids' stopping rule, all sharing one hit recorder and one mailbox. The
// hits of the levels are merged by distance through the recorder (each walk
// is limited to the closest hit so far), and the walk ends as soon as the
// next level begins beyond the closest hit: no level can then produce a
// closer one (early termination).
//
// Each level's box is enlarged by the assignment margin before clipping, so
// a triangle reaching out of the box by less than the margin is still met;
// the DDA clamps the entry cell into the level's grid.
#include <algorithm>
#include <cstdint>

#include "accel/grid/grid_ray_query.h"
#include "accel/hgrid/hgrid.h"

namespace raylab {

struct HgridView {
  const Hgrid* g = nullptr;
};

template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_hgrid(const Hgrid& g, const Ray& ray, TraversalStats* stats) {
  using Recorder = HitRecorder<kAnyHit, kCount>;
  if (g.empty || !ray_is_valid(ray)) return Recorder(ray, stats).hit();
  const DdaRay dr(ray);
  struct Pending {
    double t0, t1;
    const HgridLevel* level;
  };
  Pending pending[kHgridMaxLevels];
  int count = 0;
  for (const HgridLevel& L : g.levels) {
    const Vec3d margin = assignment_margin(L.grid);
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = L.grid.lo[a] - margin[a];
      hi[a] = L.grid.hi[a] + margin[a];
    }
    double t0 = ray.tmin, t1 = ray.tmax;
    if (!dda_clip(dr, lo, hi, t0, t1)) continue;
    int i = count++;
    while (i > 0 && pending[i - 1].t0 > t0) {
      pending[i] = pending[i - 1];
      --i;
    }
    pending[i] = Pending{t0, t1, &L};
  }
  GridRayQuery<kTest, Recorder> q(ray, stats);
  for (int i = 0; i < count; ++i) {
    const Pending& p = pending[i];
    if (q.rec.found() && p.t0 > static_cast<double>(q.rec.hit().t)) break;  // no closer hit can follow
    const double t1 = std::min(p.t1, static_cast<double>(q.rec.tmax()));
    if (p.t0 > t1) continue;
    const DdaGrid& dg = p.level->grid;
    const int level = p.level->level;
    bool stop_all = false;
    if (g.neighbours == HgridNeighbours::Store) {
      dda_walk(dg, dr, p.t0, t1, [&](int64_t cell, double, double t_exit) {
        q.rec.count_nodes(1);
        const CellSlot* s = g.cells.find(hgrid_key(level, cell));
        if (!s) return false;
        if (q.test_cell(g.refs.data() + s->begin, s->count, g.tris.data())) return stop_all = true;
        if constexpr (kAnyHit) return false;
        return q.done_at(t_exit);
      });
    } else {
      dda_walk(dg, dr, p.t0, t1, [&](int64_t cell, double, double t_exit) {
        q.rec.count_nodes(1);
        const int64_t z = cell / dg.stride[2], y = (cell % dg.stride[2]) / dg.stride[1], x = cell % dg.stride[1];
        for (int64_t dz = -1; dz <= 1; ++dz) {
          if (static_cast<uint64_t>(z + dz) >= static_cast<uint64_t>(dg.res[2])) continue;
          for (int64_t dy = -1; dy <= 1; ++dy) {
            if (static_cast<uint64_t>(y + dy) >= static_cast<uint64_t>(dg.res[1])) continue;
            for (int64_t dx = -1; dx <= 1; ++dx) {
              if (static_cast<uint64_t>(x + dx) >= static_cast<uint64_t>(dg.res[0])) continue;
              const CellSlot* s = g.cells.find(hgrid_key(level, cell + dx + dy * dg.stride[1] + dz * dg.stride[2]));
              if (s && q.test_cell(g.refs.data() + s->begin, s->count, g.tris.data())) return stop_all = true;
            }
          }
        }
        if constexpr (kAnyHit) return false;
        return q.done_at(t_exit);
      });
    }
    if (stop_all) break;
  }
  return q.rec.hit();
}

}  // namespace raylab
