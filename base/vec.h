#pragma once
// Vector types shared by every part of raylab: Eigen's fixed-size vectors.
// Vector3f is deliberately the non-aligned 12-byte type, so rays, meshes and
// nodes can be packed into flat arrays without padding.
#include <Eigen/Core>
#include <Eigen/Geometry>  // cross products

namespace raylab {

using Vec3f = Eigen::Vector3f;
using Vec3d = Eigen::Vector3d;

}  // namespace raylab
