#pragma once
// A scene: one triangle mesh, one material per triangle, a camera view and
// the radiance of rays that leave the scene. Only what the tracer needs:
// diffuse albedo and emission.
#include <cstdint>
#include <string>
#include <vector>

#include "accel/core/aabb.h"
#include "accel/core/triangle_mesh.h"

namespace raylab {

struct Material {
  Vec3f albedo = Vec3f::Constant(0.7f);   // Lambertian reflectance in [0, 1)
  Vec3f emission = Vec3f::Zero();         // radiance emitted from the front face

  bool is_emissive() const { return emission.maxCoeff() > 0.0f; }
};

// A pinhole view: eye point, look-at point, up vector, vertical field of view.
struct View {
  Vec3f from = Vec3f(0, 0, 5);
  Vec3f at = Vec3f::Zero();
  Vec3f up = Vec3f::UnitY();
  float fov_deg = 45.0f;
  int width = 512;
  int height = 512;
};

struct Scene {
  std::string name;
  TriangleMesh mesh;
  std::vector<uint32_t> material_ids;  // one per triangle, indexes materials
  std::vector<Material> materials;
  View view;
  // Radiance seen by rays that leave the scene: the default light of mesh
  // files without emitters (a uniform sky). Black for closed scenes.
  Vec3f background = Vec3f::Zero();
  // A distant key light (a "sun") for mesh files without emitters, so a plain
  // mesh shows its shape and casts shadows instead of a flat silhouette under
  // a uniform sky: irradiance on a surface facing it (zero = none), arriving
  // from the unit direction key_light_dir (pointing towards the light).
  Vec3f key_light = Vec3f::Zero();
  Vec3f key_light_dir = Vec3f::UnitY();

  size_t num_triangles() const { return mesh.num_triangles(); }
  Aabb bounds() const { return mesh.bounds(); }
  const Material& material_of(uint32_t tri) const { return materials[material_ids[tri]]; }
  bool has_emitters() const;

  // Throws MeshError / std::runtime_error on inconsistent data.
  void validate() const;
};

// What is wrong with a view (empty if nothing): non-finite vectors, `from`
// equal to `at`, `up` parallel to the viewing direction, a field of view
// outside (0, 180) degrees, an image size outside 1..65536.
std::string view_problem(const View& v);

// A camera looking at the box from a fixed oblique direction (y up), far
// enough that the bounding sphere fits the vertical field of view.
// Puts the key light above, to the left of and behind the camera (the
// photographer's key-light position), relative to scene.view; call again
// after changing the view.
void aim_key_light(Scene& scene);

View frame_bounds(const Aabb& box, int width = 512, int height = 512, float fov_deg = 45.0f);

}  // namespace raylab
