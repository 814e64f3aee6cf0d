#pragma once
// The per-ray state every grid kernel carries through its walk: the triangle
// test's precomputation, the mailbox, the closest hit so far.
//
// Termination rule (closest hit): after a cell's triangles are tested, the
// walk stops only if the closest hit so far lies within the part of the ray
// already walked (hit.t <= the cell's t_exit). A hit farther away, found on a
// triangle that extends into later cells, is kept (it shortens tmax for
// every later test) but not accepted yet: a nearer triangle may still wait in
// the next cell. This is also what makes mailboxing safe: a triangle skipped
// by the mailbox has already had its hit recorded.
#include <cstdint>

#include "accel/accelerator.h"
#include "accel/core/intersect_triangle.h"
#include "accel/grid/grid_triangles.h"
#include "accel/grid/mailbox.h"

namespace raylab {

template <TriangleTest kTest>
struct GridRayQuery {
  const Ray& ray;
  TrianglePrecompute<kTest> pre;
  RayMailbox mailbox;
  Hit hit;
  float tmax;

  explicit GridRayQuery(const Ray& r) : ray(r), pre(r), tmax(r.tmax) {}

  // Tests the triangles ids[0..count) not yet tested by this ray. Returns
  // true when kAnyHit and a hit was found (the caller stops).
  template <bool kAnyHit, bool kCount>
  bool test_cell(const uint32_t* ids, uint32_t count, const GridTriangle* tris, TraversalStats* stats) {
    for (uint32_t i = 0; i < count; ++i) {
      const uint32_t id = ids[i];
      if (mailbox.seen(id)) continue;
      if constexpr (kCount) stats->triangle_tests++;
      const GridTriangle& tri = tris[id];
      float t, u, v;
      if (pre.intersect(ray, tri.p0, tri.p1, tri.p2, ray.tmin, tmax, t, u, v)) {
        if (t < tmax || !hit.valid()) {
          hit = Hit{t, u, v, id};
          tmax = t;
          if constexpr (kAnyHit) return true;
        }
      }
    }
    return false;
  }

  // Closest hit: true once the best hit lies within [.., t_exit].
  bool done_at(double t_exit) const { return hit.valid() && static_cast<double>(hit.t) <= t_exit; }
};

}  // namespace raylab
