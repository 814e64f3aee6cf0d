#pragma once
// The one hit record: distance, barycentrics and primitive id.
#include <cstdint>
#include <limits>

namespace raylab {

// Primitive id of a miss. Every accelerator reports misses with this id
// (and t = +inf); no valid triangle index can take this value because meshes
// are limited to fewer than 2^32 - 1 triangles.
inline constexpr uint32_t kInvalidPrim = 0xFFFFFFFFu;

struct Hit {
  float t = std::numeric_limits<float>::infinity();
  // Barycentric coordinates: the hit point is (1-u-v)*v0 + u*v1 + v*v2
  // (the same convention as Embree).
  float u = 0.0f;
  float v = 0.0f;
  uint32_t prim = kInvalidPrim;

  bool valid() const { return prim != kInvalidPrim; }
};

}  // namespace raylab
