#pragma once
// Hierarchical grid walk (hgrid.h): every occupied level's box is clipped
// against the ray and each level gets its own 3D-DDA (Amanatides & Woo
// 1987, as accel/grid/dda.h, kept as a resumable state here). The walks are
// merged by distance: the next cell visited is always the one, over all
// levels, that the ray enters first, so the cells of all levels are visited
// in one front-to-back order, sharing one hit recorder and one mailbox. The
// walk ends as soon as the next cell begins beyond the closest hit so far:
// no level can then produce a closer one (early termination). A triangle
// whose hit lies at t is listed in the cell holding that point (or, with
// neighbours=pad, next to it), which starts at or before t, so it was tested.
//
// Each level's box is enlarged by the assignment margin before clipping, so
// a triangle reaching out of the box by less than the margin is still met;
// the DDA clamps the entry cell into the level's grid.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "accel/core/grid/grid_ray_query.h"
#include "accel/hgrid/hgrid.h"

namespace raylab {


// The resumable 3D-DDA of one level: the current cell and the distances to
// its next boundary on each axis (double precision, as dda_walk).
struct HgridWalk {
  const DdaGrid* grid;
  int level;
  int32_t c[3];
  int64_t index;
  double next[3], delta[3];
  double t_enter, t1;

  void start(const DdaGrid& g, int lvl, const DdaRay& r, double t0, double t_end) {
    grid = &g;
    level = lvl;
    t_enter = t0;
    t1 = t_end;
    index = 0;
    for (int a = 0; a < 3; ++a) {
      c[a] = g.coord(a, r.org[a] + t0 * r.dir[a]);
      index += c[a] * g.stride[a];
      if (r.step[a] > 0) next[a] = (g.boundary(a, c[a] + 1) - r.org[a]) * r.inv_dir[a];
      else if (r.step[a] < 0) next[a] = (g.boundary(a, c[a]) - r.org[a]) * r.inv_dir[a];
      else next[a] = std::numeric_limits<double>::infinity();
      delta[a] = r.step[a] != 0 ? g.cell[a] * std::fabs(r.inv_dir[a]) : 0.0;
    }
  }
  double t_exit() const { return std::min({next[0], next[1], next[2], t1}); }
  // Steps into the next cell; false when the ray leaves the level's box or passes t1.
  bool step(const DdaRay& r) {
    const int a = next[0] < next[1] ? (next[0] < next[2] ? 0 : 2) : (next[1] < next[2] ? 1 : 2);
    if (!(next[a] < t1)) return false;
    t_enter = next[a];
    c[a] += r.step[a];
    if (static_cast<uint32_t>(c[a]) >= static_cast<uint32_t>(grid->res[a])) return false;
    index += r.step[a] * grid->stride[a];
    next[a] += delta[a];
    return true;
  }
};

template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_hgrid(const Hgrid& g, const Ray& ray, TraversalStats* stats) {
  using Recorder = HitRecorder<kAnyHit, kCount>;
  if (g.empty || !ray_is_valid(ray)) return Recorder(ray, stats).hit();
  // Rebased on the levels' common box when the ray comes from far away
  // (dda.h, dda_line): walk parameters are s = t - t_base.
  const DdaLine line = dda_line(ray, g.lo, g.hi);
  const DdaRay& dr = line.ray;
  HgridWalk walks[kHgridMaxLevels];
  int active = 0;
  for (const HgridLevel& L : g.levels) {
    const Vec3d margin = assignment_margin(L.grid);
    double lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = L.grid.lo[a] - margin[a];
      hi[a] = L.grid.hi[a] + margin[a];
    }
    double t0 = line.smin, t1 = line.smax;
    if (!dda_clip(dr, lo, hi, t0, t1)) continue;
    walks[active++].start(L.grid, L.level, dr, t0, t1);
  }
  GridRayQuery<kTest, Recorder> q(ray, stats);
  auto test = [&](int level, int64_t cell) {
    const CellSlot* s = g.cells.find(hgrid_key(level, cell));
    q.rec.count_leaf(s ? s->count : 0);
    return s && q.test_cell(g.refs.data() + s->begin, s->count, g.tris.data());
  };
  while (active > 0) {
    // The level whose current cell the ray enters first.
    int best = 0;
    for (int i = 1; i < active; ++i)
      if (walks[i].t_enter < walks[best].t_enter) best = i;
    HgridWalk& w = walks[best];
    if (q.rec.found() && line.t_base + w.t_enter > static_cast<double>(q.rec.hit().t)) break;  // no closer hit can follow
    q.rec.count_inner();
    if (g.neighbours == HgridNeighbours::Store) {
      if (test(w.level, w.index)) break;  // any hit: found
    } else {
      const DdaGrid& dg = *w.grid;
      bool stop = false;
      for (int dz = -1; dz <= 1 && !stop; ++dz) {
        if (static_cast<uint32_t>(w.c[2] + dz) >= static_cast<uint32_t>(dg.res[2])) continue;
        for (int dy = -1; dy <= 1 && !stop; ++dy) {
          if (static_cast<uint32_t>(w.c[1] + dy) >= static_cast<uint32_t>(dg.res[1])) continue;
          for (int dx = -1; dx <= 1 && !stop; ++dx) {
            if (static_cast<uint32_t>(w.c[0] + dx) >= static_cast<uint32_t>(dg.res[0])) continue;
            stop = test(w.level, w.index + dx + dy * dg.stride[1] + dz * dg.stride[2]);
          }
        }
      }
      if (stop) break;
    }
    if (!w.step(dr)) walks[best] = walks[--active];
  }
  return q.rec.hit();
}

// The walk under the name the generic shell calls (accel/core/view_accelerator.h).
template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_view(const Hgrid& v, const Ray& ray, TraversalStats* stats) { return traverse_hgrid<kTest, kAnyHit, kCount>(v, ray, stats); }

}  // namespace raylab
