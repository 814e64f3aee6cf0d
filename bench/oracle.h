#pragma once
// Independent referee for disagreements between an accelerator and Embree:
// every triangle tested in double precision with the watertight test's
// algorithm. It also reports whether the ray passes within a relative
// distance `graze_tol` of some triangle's edge (or of its tmin/tmax), where
// float computations may legitimately decide either way. Rays through edges
// and vertices exactly need exact arithmetic (a later refinement); such rays
// are reported as grazing here, not as errors.
#include <cstdint>

#include "accel/core/hit.h"
#include "accel/core/ray.h"
#include "accel/core/triangle_mesh.h"

namespace raylab {

struct OracleHit {
  bool valid = false;
  double t = 0.0;
  uint32_t prim = kInvalidPrim;
  bool grazing = false;
};

OracleHit oracle_closest_hit(const TriangleMesh& mesh, const Ray& ray, double graze_tol = 1e-5);

}  // namespace raylab
