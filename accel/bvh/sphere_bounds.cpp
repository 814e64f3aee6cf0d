#include "accel/bvh/sphere_bounds.h"

#include <algorithm>
#include <limits>

namespace raylab {

Sphere ritter_sphere(std::span<const Vec3f> points) {
  Sphere s;
  if (points.empty()) return s;
  auto farthest_from = [&](const Vec3d& p) {
    double best = -1.0;
    Vec3d far = p;
    for (const Vec3f& q : points) {
      const double d = (q.cast<double>() - p).squaredNorm();
      if (d > best) {
        best = d;
        far = q.cast<double>();
      }
    }
    return far;
  };
  const Vec3d y = farthest_from(points[0].cast<double>());
  const Vec3d z = farthest_from(y);
  Vec3d c = 0.5 * (y + z);
  double r = 0.5 * (z - y).norm();
  // Grow: a point outside moves the sphere towards it just enough to hold it
  // and everything the old sphere held.
  for (const Vec3f& qf : points) {
    const Vec3d q = qf.cast<double>();
    const double d = (q - c).norm();
    if (d > r) {
      const double r_new = 0.5 * (r + d);
      c += (r_new - r) / d * (q - c);
      r = r_new;
    }
  }
  // The float centre differs from c; take the exact largest distance from it.
  s.center = c.cast<float>();
  const Vec3d cf = s.center.cast<double>();
  double r2 = 0.0;
  for (const Vec3f& q : points) r2 = std::max(r2, (q.cast<double>() - cf).squaredNorm());
  const double padded = std::sqrt(r2) * (1.0 + 0x1p-20) + 1e-30;
  float rf = static_cast<float>(padded);
  if (static_cast<double>(rf) < padded) rf = std::nextafter(rf, std::numeric_limits<float>::infinity());
  s.radius = rf;
  return s;
}

}  // namespace raylab
