#pragma once
// Render's camera and look options, pbrt/Mitsuba style:
//   --camera from=x,y,z,at=x,y,z,up=x,y,z,fov=deg   (any subset; the rest
//            keeps the scene's own camera)
//   --up x|y|z|-x|-y|-z  which axis of a mesh file points up (Z-up files from
//            Blender, DXF, STL...): the mesh is turned so that axis becomes +y
//            and the default camera re-framed
//   --background v | r,g,b  radiance of rays leaving the scene
#include <string>

#include "scenes/scene.h"

namespace raylab::cli {

// Applies "from=..,at=..,up=..,fov=.." to `view`; throws std::invalid_argument
// naming the bad key or value.
void apply_camera_option(const std::string& text, View& view);

// Turns the scene so `axis` ("z", "-y"...) becomes +y and re-frames the view.
void apply_up_axis(const std::string& axis, Scene& scene);

// "0.2" (grey) or "r,g,b" (linear radiance, each >= 0).
Vec3f parse_background(const std::string& text);

}  // namespace raylab::cli
