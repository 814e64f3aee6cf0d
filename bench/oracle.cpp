#include "bench/oracle.h"

#include <cmath>
#include <utility>

namespace raylab {

OracleHit oracle_closest_hit(const TriangleMesh& mesh, const Ray& ray, double graze_tol) {
  OracleHit best;
  if (!ray_is_valid(ray)) return best;
  const Vec3d o = ray.org.cast<double>();
  const Vec3d d = ray.dir.cast<double>();
  const Vec3d ad = d.cwiseAbs();
  int kz = (ad.x() >= ad.y()) ? (ad.x() >= ad.z() ? 0 : 2) : (ad.y() >= ad.z() ? 1 : 2);
  int kx = (kz + 1) % 3, ky = (kx + 1) % 3;
  if (d[kz] < 0.0) std::swap(kx, ky);
  const double sx = d[kx] / d[kz], sy = d[ky] / d[kz], sz = 1.0 / d[kz];
  const double tmin = ray.tmin, tmax = ray.tmax;

  for (size_t i = 0; i < mesh.num_triangles(); ++i) {
    const Vec3d a = mesh.vertex(i, 0).cast<double>() - o;
    const Vec3d b = mesh.vertex(i, 1).cast<double>() - o;
    const Vec3d c = mesh.vertex(i, 2).cast<double>() - o;
    const double ax = a[kx] - sx * a[kz], ay = a[ky] - sy * a[kz];
    const double bx = b[kx] - sx * b[kz], by = b[ky] - sy * b[kz];
    const double cx = c[kx] - sx * c[kz], cy = c[ky] - sy * c[kz];
    const double u = cx * by - cy * bx;
    const double v = ax * cy - ay * cx;
    const double w = bx * ay - by * ax;
    const double det = u + v + w;
    if (det == 0.0) continue;
    const double t = (u * sz * a[kz] + v * sz * b[kz] + w * sz * c[kz]) / det;
    if (!std::isfinite(t)) continue;
    const double bu = u / det, bv = v / det, bw = w / det;
    const double margin = std::min({bu, bv, bw});
    const double t_slack = graze_tol * std::max(1.0, std::fabs(t));
    const bool in_range = t >= tmin - t_slack && t <= tmax + t_slack;
    if (in_range && std::fabs(margin) < graze_tol) best.grazing = true;
    if (in_range && margin >= -graze_tol && (std::fabs(t - tmin) < t_slack || std::fabs(t - tmax) < t_slack))
      best.grazing = true;
    if (margin < 0.0 || t < tmin || t > tmax) continue;
    if (!best.valid || t < best.t) {
      best.valid = true;
      best.t = t;
      best.prim = static_cast<uint32_t>(i);
    }
  }
  return best;
}

}  // namespace raylab
