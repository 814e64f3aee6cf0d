#pragma once
// The walk of the irregular grid (Perard-Gayot et al. 2017, section 5): find
// the cell holding the current point in the voxel map, test its triangles,
// leave through the nearest face of the cell's (expanded) box, and look up
// the cell just past that face.
//
// Robust stepping, on integer virtual-voxel coordinates v instead of a point
// nudged past the exit: on the exit axis v moves to the first voxel beyond
// the box's face (hi, or lo - 1); on the other axes v takes the voxel of the
// exit point, clamped between its old value and the box's far side in the
// direction of travel. So v never moves backwards and strictly advances on
// one axis per step: the walk ends after at most the sum of the virtual
// resolutions, whatever the rounding. A direction component of +-0 never
// gives an exit and keeps its coordinate (the ray stays in its slab; a ray
// lying in a cell face is in the cell above it, and the assignment margin
// lists triangles on the face in both cells).
//
// Exactness (closest hit): every triangle of a visited cell is tested on the
// recorder's whole [tmin, tmax], and the walk stops only once the closest
// hit lies within the part of the ray walked so far (t <= the cell's exit,
// grid_ray_query.h). Expansion keeps this: a cell's box only grows over
// voxels whose owners' triangles the cell lists (or that are empty), so all
// triangles within the assignment margin of the walked path were tested.
//
// Triangle tests: every triangle of a visited cell, without a mailbox: a
// triangle met again in a later cell is tested again, which cannot change
// the recorder's hit (the same t and id; ties go to the lower id). With leaf
// blocks (kBlocks, irgrid.h) `cur` is a cell's slab position and its
// triangles are tested 8 at a time by the SIMD watertight test; simd=0 runs
// the same walk with the scalar test, so both give the same hits and count
// the same work (a mailbox cannot skip single lanes of a block).
#include <cmath>
#include <cstdint>
#include <limits>

#include "accel/core/simd/triangle_block.h"
#include "accel/core/grid/grid_ray_query.h"
#include "accel/irgrid/irgrid.h"

namespace raylab {

template <TriangleTest kTest, bool kAnyHit, bool kCount, bool kBlocks = false, bool kFarFirst = false>
inline Hit traverse_irgrid(const Irgrid& g, const Ray& ray, TraversalStats* stats) {
  static_assert(!kBlocks || kTest == TriangleTest::Watertight, "the SIMD leaves run the watertight test");
  // kFarFirst: walk_grid hands the walk the reversed line (any hit from the
  // far end); the expanded boxes' faces serve either direction.
  return walk_grid<kTest, kAnyHit, kCount, kBlocks, kFarFirst, kIrgridBlockWidth>(g.virt, g.empty, ray, stats, [&](const DdaRay& dr, double t0,
                                                                                    double t1, auto& q) {
    int32_t v[3];
    for (int a = 0; a < 3; ++a) v[a] = g.virt.coord(a, dr.org[a] + t0 * dr.dir[a]);
    // Per-ray constants of the step (one FMA per axis instead of four
    // dependent operations): the distance to virtual boundary c on axis a is
    // c * exit_scale + exit_base, +inf on an axis the ray does not move
    // along; the virtual coordinate of the point at distance t is
    // floor(t * voxel_scale + voxel_base). They round differently from
    // boundary() and coord(), by a few ulps in double, far below the cells'
    // assignment margin (dda_grid.h), and the clamping below keeps the walk
    // monotone whatever the rounding.
    double exit_scale[3], exit_base[3], voxel_scale[3], voxel_base[3];
    int face_hi[3];  // 1: the ray leaves a box through its hi face on axis a
    for (int a = 0; a < 3; ++a) {
      face_hi[a] = dr.step[a] > 0;
      voxel_scale[a] = dr.dir[a] * g.virt.inv_cell[a];
      voxel_base[a] = (dr.org[a] - g.virt.lo[a]) * g.virt.inv_cell[a];
      if (dr.step[a] == 0) {
        exit_scale[a] = 0.0;
        exit_base[a] = std::numeric_limits<double>::infinity();
      } else {
        exit_scale[a] = g.virt.cell[a] * dr.inv_dir[a];
        exit_base[a] = (g.virt.lo[a] - dr.org[a]) * dr.inv_dir[a];
      }
    }
    const IrgridCell* cells = g.cells.data();
    const uint32_t* refs = g.refs.data();
    const LeafTriangle* tris = g.tris.data();
    Irgrid::LookupCache cache;
    // Software pipelining: the walk is a chain of dependent loads (voxel
    // map -> cell -> triangles), so each step first finds the *next* cell
    // (it depends only on the current cell's box, not on its triangles) and
    // only then tests the current cell's triangles: the next lookup's loads
    // overlap the triangle tests instead of waiting behind them.
    uint32_t cur = g.cell_at(v, cache);
    while (true) {
      // With blocks, `cur` is the cell's slab position (irgrid.h).
      const IrgridCell& c = kBlocks ? g.slab_cell(cur) : cells[cur];
      q.rec.count_cell(c.count);
      double t_face[3];
      for (int a = 0; a < 3; ++a)
        t_face[a] = std::fma(static_cast<double>(face_hi[a] ? c.hi[a] : c.lo[a]), exit_scale[a], exit_base[a]);
      // The nearest face; ties to x, then y (a valid ray moves along some axis).
      int exit_axis = t_face[1] < t_face[0] ? 1 : 0;
      exit_axis = t_face[2] < t_face[exit_axis] ? 2 : exit_axis;
      const double t_exit = t_face[exit_axis];
      // The next voxel, then its cell (none past the ray's end or the grid).
      bool last = !(t_exit < t1);
      uint32_t next = 0;
      if (!last) {
        for (int a = 0; a < 3; ++a) {
          if (a == exit_axis || dr.step[a] == 0) continue;
          const double f = std::floor(std::fma(t_exit, voxel_scale[a], voxel_base[a]));
          const int32_t at = !(f >= 0.0) ? 0 : (f >= g.virt.res[a] ? g.virt.res[a] - 1 : static_cast<int32_t>(f));
          if (dr.step[a] > 0) v[a] = at < v[a] ? v[a] : (at >= c.hi[a] ? c.hi[a] - 1 : at);
          else v[a] = at > v[a] ? v[a] : (at < c.lo[a] ? c.lo[a] : at);
        }
        v[exit_axis] = dr.step[exit_axis] > 0 ? c.hi[exit_axis] : c.lo[exit_axis] - 1;
        last = static_cast<uint32_t>(v[exit_axis]) >= static_cast<uint32_t>(g.virt.res[exit_axis]);
        if (!last) {
          next = g.cell_at(v, cache);
          if constexpr (kBlocks) {
            // The record and the first block's vertices (the record is
            // 64 bytes: a line each).
            const char* p = reinterpret_cast<const char*>(g.slabs.data() + next);
            __builtin_prefetch(p);
            __builtin_prefetch(p + 64);
            __builtin_prefetch(p + 128);
            __builtin_prefetch(p + 192);
          } else {
            __builtin_prefetch(cells + next);
          }
        }
      }
      if constexpr (kBlocks) {
        if (c.count != 0 && intersect_block_leaf<kIrgridBlockWidth>(g.slab_blocks(cur), irgrid_blocks(c.count), q.block_ray,
                                                                 q.ray.tmin, q.rec)) {
          if constexpr (kAnyHit) return;  // found one
        }
      } else {
        if (c.count != 0 && intersect_leaf_indexed(q.pre, q.ray, tris, refs + c.begin, c.count, q.rec)) {
          if constexpr (kAnyHit) return;  // found one
        }
      }
      if constexpr (!kAnyHit) {
        if (q.done_at(t_exit)) return;
      }
      if (last) return;
      cur = next;
    }
  });
}

}  // namespace raylab
