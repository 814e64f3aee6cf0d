#include "scenes/scene.h"

#include <cmath>

#include <fmt/format.h>

namespace raylab {

bool Scene::has_emitters() const {
  for (const auto& m : materials)
    if (m.is_emissive()) return true;
  return false;
}

void Scene::validate() const {
  mesh.validate();
  if (material_ids.size() != mesh.num_triangles())
    throw MeshError(fmt::format("scene '{}': {} material ids for {} triangles", name, material_ids.size(),
                                mesh.num_triangles()));
  for (size_t i = 0; i < material_ids.size(); ++i)
    if (material_ids[i] >= materials.size())
      throw MeshError(fmt::format("scene '{}': triangle {} uses material {}, but there are {} materials", name, i,
                                  material_ids[i], materials.size()));
}

std::string view_problem(const View& v) {
  if (!v.from.allFinite() || !v.at.allFinite() || !v.up.allFinite()) return "camera vectors must be finite";
  const Vec3f forward = v.at - v.from;
  if (!(forward.norm() > 0.0f)) return "camera 'from' and 'at' are the same point";
  if (!(v.up.norm() > 0.0f)) return "camera 'up' is the zero vector";
  if (!(forward.normalized().cross(v.up.normalized()).norm() > 1e-6f)) return "camera 'up' is parallel to the viewing direction";
  if (!(v.fov_deg > 0.0f && v.fov_deg < 180.0f)) return fmt::format("field of view {} degrees is outside (0, 180)", v.fov_deg);
  if (v.width < 1 || v.width > 65536 || v.height < 1 || v.height > 65536)
    return fmt::format("image size {}x{} is outside 1..65536", v.width, v.height);
  return "";
}

void aim_key_light(Scene& scene) {
  const View& v = scene.view;
  const Vec3f forward = (v.at - v.from).normalized();
  const Vec3f right = forward.cross(v.up).normalized();
  const Vec3f up = right.cross(forward);
  const Vec3f dir = 0.8f * up - 0.5f * right - 0.45f * forward;
  if (dir.allFinite() && dir.squaredNorm() > 0) scene.key_light_dir = dir.normalized();
}

View frame_bounds(const Aabb& box, int width, int height, float fov_deg) {
  View v;
  v.width = width;
  v.height = height;
  v.fov_deg = fov_deg;
  v.up = Vec3f::UnitY();
  if (box.is_empty()) return v;
  const Vec3f c = box.center();
  const float radius = std::max(0.5f * box.diagonal().norm(), 1e-30f);
  const float half = 0.5f * fov_deg * static_cast<float>(M_PI) / 180.0f;
  const float dist = 1.1f * radius / std::sin(half);
  const Vec3f dir = Vec3f(0.55f, 0.45f, 1.0f).normalized();
  v.at = c;
  v.from = c + dist * dir;
  return v;
}

}  // namespace raylab
