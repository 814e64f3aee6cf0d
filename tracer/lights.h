#pragma once
// Emissive triangles as area lights, chosen in proportion to emitted power
// (area x luminance of emission) for next-event estimation.
#include <cstdint>
#include <vector>

#include "scenes/scene.h"

namespace raylab {

class LightSampler {
 public:
  explicit LightSampler(const Scene& scene);

  bool empty() const { return lights_.empty(); }
  size_t size() const { return lights_.size(); }

  struct Sample {
    Vec3f point;
    Vec3f normal;     // unit front-face normal of the light
    Vec3f emission;
    float pdf_area;   // probability density per unit area (selection included)
    uint32_t prim;
  };

  // u0 picks the triangle, (u1, u2) the point on it.
  Sample sample(float u0, float u1, float u2) const;

  // Area density of having sampled a point on triangle `prim` (0 if not a light).
  float pdf_area(uint32_t prim) const { return prim < pdf_area_of_.size() ? pdf_area_of_[prim] : 0.0f; }

 private:
  const Scene& scene_;
  std::vector<uint32_t> lights_;   // triangle ids
  std::vector<float> cdf_;         // cumulative selection probability
  std::vector<float> pdf_area_of_; // per triangle: selection prob / area
};

}  // namespace raylab
