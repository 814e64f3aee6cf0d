// The Cornell box, from the measurements published by the Cornell Program of
// Computer Graphics ("Cornell Box Data"): coordinates in millimetres, camera
// at (278, 273, -800) looking down +z, 35 mm focal length on a 25 mm film.
// The geometry is base/mesh_shapes.h's cornell_box_mesh(). Reflectances and
// emission are the RGB values commonly used for this scene.
#include "scenes/procedural.h"

namespace raylab {

Scene make_cornell_box() {
  Scene s;
  s.name = "cornell";
  enum : uint32_t { kWhite, kRed, kGreen, kLight };
  s.materials = {
      Material{Vec3f(0.725f, 0.71f, 0.68f), Vec3f::Zero()},
      Material{Vec3f(0.63f, 0.065f, 0.05f), Vec3f::Zero()},
      Material{Vec3f(0.14f, 0.45f, 0.091f), Vec3f::Zero()},
      Material{Vec3f(0.78f, 0.78f, 0.78f), Vec3f(17.0f, 12.0f, 4.0f)},
  };
  s.mesh = cornell_box_mesh();  // base/mesh_shapes.h: the geometry, two triangles per quad
  for (size_t tri = 0; tri < s.mesh.num_triangles(); ++tri) {
    const int quad = static_cast<int>(tri / 2);
    s.material_ids.push_back(quad == kCornellGreenQuad ? kGreen
                             : quad == kCornellRedQuad ? kRed
                             : quad == kCornellLightQuad ? kLight
                                                         : kWhite);
  }

  s.view.from = Vec3f(278.0f, 273.0f, -800.0f);
  s.view.at = Vec3f(278.0f, 273.0f, 0.0f);
  s.view.up = Vec3f::UnitY();
  s.view.fov_deg = 39.3077f;  // 2 * atan(12.5 / 35) in degrees
  s.view.width = 512;
  s.view.height = 512;
  s.background = Vec3f::Zero();
  return s;
}

}  // namespace raylab
