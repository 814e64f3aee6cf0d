#pragma once
// Sampling routines for the path tracer.
#include <cmath>

#include "base/vec.h"

namespace raylab {

inline constexpr float kPi = 3.14159265358979323846f;
inline constexpr float kInvPi = 1.0f / kPi;

// Orthonormal basis around a unit normal without branches on the normal's
// direction except its sign (Duff et al., "Building an Orthonormal Basis,
// Revisited", JCGT 2017).
inline void orthonormal_basis(const Vec3f& n, Vec3f& t, Vec3f& b) {
  const float sign = std::copysign(1.0f, n.z());
  const float a = -1.0f / (sign + n.z());
  const float c = n.x() * n.y() * a;
  t = Vec3f(1.0f + sign * n.x() * n.x() * a, sign * c, -sign * n.x());
  b = Vec3f(c, sign + n.y() * n.y() * a, -n.y());
}

// Cosine-weighted direction about n (Malley's method: uniform disk point
// projected up); pdf = cos(theta) / pi.
inline Vec3f sample_cosine_hemisphere(const Vec3f& n, float u1, float u2, float& pdf) {
  const float r = std::sqrt(u1);
  const float phi = 2.0f * kPi * u2;
  const float x = r * std::cos(phi), y = r * std::sin(phi);
  const float z = std::sqrt(std::max(0.0f, 1.0f - u1));
  Vec3f t, b;
  orthonormal_basis(n, t, b);
  pdf = z * kInvPi;
  return (x * t + y * b + z * n).normalized();
}

// Uniform point on a triangle (square-root parameterisation).
inline Vec3f sample_triangle(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, float u1, float u2) {
  const float su = std::sqrt(u1);
  const float b0 = 1.0f - su, b1 = u2 * su;
  return b0 * p0 + b1 * p1 + (1.0f - b0 - b1) * p2;
}

inline float luminance(const Vec3f& c) { return 0.2126f * c.x() + 0.7152f * c.y() + 0.0722f * c.z(); }

}  // namespace raylab
