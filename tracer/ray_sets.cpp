#include "tracer/ray_sets.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "base/spec.h"
#include "tracer/camera.h"
#include "tracer/lights.h"
#include "base/pcg.h"
#include "tracer/sampling.h"
#include "tracer/spawn.h"

namespace raylab {

const std::vector<std::string>& ray_set_names() {
  static const std::vector<std::string> names = {"primary", "diffuse", "shadow", "random"};
  return names;
}

RaySet make_primary_rays(const Scene& scene, int width, int height) {
  View v = scene.view;
  v.width = width;
  v.height = height;
  const PinholeCamera cam(v);
  RaySet set{"primary", false, {}};
  set.rays.reserve(static_cast<size_t>(width) * height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) set.rays.push_back(cam.generate(x + 0.5f, y + 0.5f));
  return set;
}

RaySet make_jittered_primary_rays(const Scene& scene, size_t count, uint64_t seed) {
  const PinholeCamera cam(scene.view);
  Pcg32 rng(mix64(seed), 0x5EED);
  RaySet set{"primary", false, {}};
  set.rays.reserve(count);
  for (size_t i = 0; i < count; ++i)
    set.rays.push_back(cam.generate(rng.uniform() * scene.view.width, rng.uniform() * scene.view.height));
  return set;
}

RaySet make_random_rays(const Scene& scene, size_t count, uint64_t seed) {
  Aabb b = scene.bounds();
  if (b.is_empty()) b = Aabb(Vec3f::Constant(-1), Vec3f::Constant(1));
  const Vec3f margin = Vec3f::Constant(0.05f * std::max(b.diagonal().norm(), 1e-30f));
  const Vec3f lo = b.lo - margin, ext = b.diagonal() + 2.0f * margin;
  Pcg32 rng(mix64(seed), 0xA11CE);
  RaySet set{"random", false, {}};
  set.rays.reserve(count);
  while (set.rays.size() < count) {
    const Vec3f a = lo + ext.cwiseProduct(Vec3f(rng.uniform(), rng.uniform(), rng.uniform()));
    const Vec3f c = lo + ext.cwiseProduct(Vec3f(rng.uniform(), rng.uniform(), rng.uniform()));
    const Vec3f d = c - a;
    const float len = d.norm();
    if (!(len > 0.0f)) continue;
    set.rays.emplace_back(a, d / len, 0.0f, len);
  }
  return set;
}

namespace {

// Hit point and the geometric normal facing the incoming ray.
bool surface_at(const Scene& scene, const Ray& ray, const Hit& hit, Vec3f& p, Vec3f& n) {
  if (!hit.valid()) return false;
  const Vec3f& p0 = scene.mesh.vertex(hit.prim, 0);
  const Vec3f& p1 = scene.mesh.vertex(hit.prim, 1);
  const Vec3f& p2 = scene.mesh.vertex(hit.prim, 2);
  const Vec3f c = (p1 - p0).cross(p2 - p0);
  const float len = c.norm();
  if (!(len > 0.0f)) return false;
  n = c / len;
  if (n.dot(ray.dir) > 0.0f) n = -n;
  p = (1.0f - hit.u - hit.v) * p0 + hit.u * p1 + hit.v * p2;
  return true;
}

}  // namespace

RaySet make_diffuse_rays(const Scene& scene, const RaySet& primary, std::span<const Hit> hits, uint64_t seed) {
  RaySet set{"diffuse", false, {}};
  Pcg32 rng(mix64(seed), 0xD1FF);
  const SpawnOffset spawn(scene.bounds());
  for (size_t i = 0; i < primary.rays.size(); ++i) {
    Vec3f p, n;
    if (!surface_at(scene, primary.rays[i], hits[i], p, n)) continue;
    float pdf;
    const Vec3f d = sample_cosine_hemisphere(n, rng.uniform(), rng.uniform(), pdf);
    set.rays.emplace_back(spawn.origin(p, n, primary.rays[i].org), d);
  }
  return set;
}

RaySet make_shadow_rays(const Scene& scene, const RaySet& primary, std::span<const Hit> hits, uint64_t seed) {
  RaySet set{"shadow", true, {}};
  Pcg32 rng(mix64(seed), 0x5AD0);
  const LightSampler lights(scene);
  const Aabb b = scene.bounds();
  const SpawnOffset spawn(scene.bounds());
  const Vec3f point_light =
      b.is_empty() ? Vec3f(0, 10, 0) : Vec3f(b.center() + b.diagonal().norm() * Vec3f(0.3f, 1.0f, 0.2f));
  for (size_t i = 0; i < primary.rays.size(); ++i) {
    Vec3f p, n;
    if (!surface_at(scene, primary.rays[i], hits[i], p, n)) continue;
    const Vec3f origin = spawn.origin(p, n, primary.rays[i].org);
    Vec3f target = point_light;
    if (!lights.empty()) target = lights.sample(rng.uniform(), rng.uniform(), rng.uniform()).point;
    if (!((target - origin).squaredNorm() > 0.0f)) continue;
    set.rays.push_back(shadow_ray_to(origin, target));
  }
  return set;
}

void check_ray_set_names(const std::vector<std::string>& names) {
  for (const auto& n : names)
    if (std::find(ray_set_names().begin(), ray_set_names().end(), n) == ray_set_names().end())
      throw SpecError(fmt::format("unknown ray set '{}' (available: {})", n, fmt::join(ray_set_names(), ", ")));
}

std::vector<RaySet> make_ray_sets(const Scene& scene, const std::vector<std::string>& names,
                                  const Accelerator& reference, const RaySetOptions& o) {
  check_ray_set_names(names);
  auto wants = [&](const char* n) {
    for (const auto& x : names)
      if (x == n) return true;
    return false;
  };
  RaySet primary = o.jittered_primary ? make_jittered_primary_rays(scene, o.primary_count, o.seed)
                                      : make_primary_rays(scene, o.width, o.height);
  std::vector<Hit> primary_hits;
  if (wants("diffuse") || wants("shadow")) {
    primary_hits.resize(primary.rays.size());
    reference.intersect(primary.rays, primary_hits);
  }
  std::vector<RaySet> out;
  for (const auto& n : names) {
    if (n == "primary") out.push_back(primary);
    else if (n == "random") out.push_back(make_random_rays(scene, o.random_count, o.seed));
    else if (n == "diffuse") out.push_back(make_diffuse_rays(scene, primary, primary_hits, o.seed));
    else if (n == "shadow") out.push_back(make_shadow_rays(scene, primary, primary_hits, o.seed));
  }
  return out;
}

}  // namespace raylab
