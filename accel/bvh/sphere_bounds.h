#pragma once
// Bounding spheres for the sphere hierarchy (`bvh:bound=sphere`).
//
// Ritter, "An Efficient Bounding Sphere", Graphics Gems (1990): start from
// the sphere on two far-apart points (a point, the point farthest from it,
// the point farthest from that), then grow it to take in every point outside
// it. Not the minimal sphere (Welzl 1991), typically within 5-20 % of its
// radius, and linear in the points. Computed in double precision, then the
// radius is rounded up and padded by a relative 2^-20 so a float ray test
// that errs by a few ulps never loses a point the sphere must hold.
#include <cmath>
#include <span>

#include "base/vec.h"

namespace raylab {

struct Sphere {
  Vec3f center = Vec3f::Zero();
  float radius = -1.0f;  // negative: empty

  double volume() const { return radius < 0 ? 0.0 : 4.0 / 3.0 * M_PI * std::pow(static_cast<double>(radius), 3); }
  double surface_area() const { return radius < 0 ? 0.0 : 4.0 * M_PI * static_cast<double>(radius) * radius; }
};

// Ritter sphere of `points`, conservative in float (see above).
Sphere ritter_sphere(std::span<const Vec3f> points);

}  // namespace raylab
