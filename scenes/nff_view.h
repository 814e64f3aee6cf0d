#pragma once
// The view record of an NFF file (Haines' Neutral File Format, the format of
// the Standard Procedural Databases). Assimp reads NFF geometry but keeps the
// view to itself, so raylab reads the record directly:
//
//   v
//   from  Fx Fy Fz        eye point
//   at    Ax Ay Az        look-at point
//   up    Ux Uy Uz        up direction
//   angle A               field of view in degrees
//   hither H              near plane (ignored: the tracer has none)
//   resolution W H        image size in pixels
//
// NFF defines `angle` between the centres of the outermost pixels; raylab's
// fov_deg spans the full image. The difference is (1 - (n-1)/n) of the
// tangent, 0.2 % at 512 pixels; like the SPD view files in ../shared,
// raylab uses the angle as the vertical field of view unchanged.
#include <optional>
#include <string>

#include "scenes/scene.h"

namespace raylab {

// The view of an NFF file, or nullopt if the file has no view record.
// Throws SceneLoadError naming the file and line when the record is
// incomplete or malformed.
std::optional<View> read_nff_view(const std::string& path);

}  // namespace raylab
