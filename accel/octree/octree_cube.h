#pragma once
// The octree's root cube and the one formula for every cell plane in it.
//
// A node at level l is addressed by integer coordinates on the finest
// lattice (kOctMaxLevel levels): its low corner is (ix, iy, iz) and its side
// 2^(kOctMaxLevel - l) lattice units. The plane at lattice coordinate i along
// axis k is lo[k] + float(i) * unit (unit = side * 2^-kOctMaxLevel, exact):
// a product and a sum, both rounded once, and — since the builder (exact
// triangle/box assignment) and the traversal (entry/exit parameters) call
// this same function — both agree on every plane bit for bit, and two
// siblings share their common face exactly.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "base/aabb.h"

namespace raylab {

// Deepest level any octree layout supports (root = level 0); the lattice has
// 2^kOctMaxLevel cells per side, so coordinates fit in float mantissas.
inline constexpr int kOctMaxLevel = 20;

struct OctreeCube {
  float lo[3] = {0, 0, 0};
  float side = 0.0f;
  float unit = 0.0f;  // side * 2^-kOctMaxLevel

  // Position of lattice plane i (0 <= i <= 2^kOctMaxLevel) along axis k.
  [[gnu::always_inline]] float plane(int k, uint32_t i) const { return lo[k] + static_cast<float>(i) * unit; }

  // Lattice units per side of a node at `level`.
  static uint32_t span(int level) { return 1u << (kOctMaxLevel - level); }

  Aabb box() const {
    const uint32_t n = span(0);
    return Aabb(Vec3f(plane(0, 0), plane(1, 0), plane(2, 0)), Vec3f(plane(0, n), plane(1, n), plane(2, n)));
  }
};

// The cube around `bounds`: the largest side, padded by 1e-5 of itself (and
// a few ulps of the coordinates) on every side, so triangles on the bounds lie
// strictly inside and a flat scene still gets a cube of non-zero side.
inline OctreeCube octree_cube_around(const Aabb& bounds) {
  OctreeCube c;
  const Vec3f ext = bounds.diagonal();
  const float largest = std::max({ext.x(), ext.y(), ext.z()});
  const float magnitude = std::max(bounds.lo.cwiseAbs().maxCoeff(), bounds.hi.cwiseAbs().maxCoeff());
  const float pad = std::max({1e-5f * largest, 1e-6f * magnitude, 1e-30f});
  const float side = largest + 4.0f * pad;
  for (int k = 0; k < 3; ++k) c.lo[k] = bounds.lo[k] - pad;
  c.side = side;
  c.unit = side * 0x1p-20f;
  // Rounding of lo + n * unit must not cut the bounds off: grow until it holds.
  for (int guard = 0; guard < 64; ++guard) {
    bool inside = true;
    for (int k = 0; k < 3; ++k) inside = inside && c.plane(k, OctreeCube::span(0)) > bounds.hi[k];
    if (inside) break;
    c.side *= 1.0f + 0x1p-10f;
    c.unit = c.side * 0x1p-20f;
  }
  return c;
}

}  // namespace raylab
