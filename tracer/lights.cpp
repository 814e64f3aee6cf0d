#include "tracer/lights.h"

#include <algorithm>

#include "tracer/sampling.h"

namespace raylab {

LightSampler::LightSampler(const Scene& scene) : scene_(scene) {
  std::vector<double> power;
  for (size_t i = 0; i < scene.num_triangles(); ++i) {
    const Material& m = scene.material_of(static_cast<uint32_t>(i));
    if (!m.is_emissive()) continue;
    const Vec3f e1 = scene.mesh.vertex(i, 1) - scene.mesh.vertex(i, 0);
    const Vec3f e2 = scene.mesh.vertex(i, 2) - scene.mesh.vertex(i, 0);
    const double area = 0.5 * static_cast<double>(e1.cross(e2).norm());
    const double p = area * luminance(m.emission);
    if (!(p > 0.0)) continue;  // zero-area emitters cannot be sampled
    lights_.push_back(static_cast<uint32_t>(i));
    power.push_back(p);
  }
  if (lights_.empty()) return;
  double total = 0.0;
  for (double p : power) total += p;
  cdf_.resize(lights_.size());
  pdf_area_of_.assign(scene.num_triangles(), 0.0f);
  double acc = 0.0;
  for (size_t k = 0; k < lights_.size(); ++k) {
    acc += power[k];
    cdf_[k] = static_cast<float>(acc / total);
    const uint32_t tri = lights_[k];
    const Vec3f e1 = scene.mesh.vertex(tri, 1) - scene.mesh.vertex(tri, 0);
    const Vec3f e2 = scene.mesh.vertex(tri, 2) - scene.mesh.vertex(tri, 0);
    const double area = 0.5 * static_cast<double>(e1.cross(e2).norm());
    pdf_area_of_[tri] = static_cast<float>((power[k] / total) / area);
  }
  cdf_.back() = 1.0f;
}

LightSampler::Sample LightSampler::sample(float u0, float u1, float u2) const {
  const size_t k = std::min<size_t>(static_cast<size_t>(std::upper_bound(cdf_.begin(), cdf_.end(), u0) - cdf_.begin()),
                                    lights_.size() - 1);
  const uint32_t tri = lights_[k];
  const Vec3f& p0 = scene_.mesh.vertex(tri, 0);
  const Vec3f& p1 = scene_.mesh.vertex(tri, 1);
  const Vec3f& p2 = scene_.mesh.vertex(tri, 2);
  Sample s;
  s.point = sample_triangle(p0, p1, p2, u1, u2);
  s.normal = (p1 - p0).cross(p2 - p0).normalized();
  s.emission = scene_.material_of(tri).emission;
  s.pdf_area = pdf_area_of_[tri];
  s.prim = tri;
  return s;
}

}  // namespace raylab
