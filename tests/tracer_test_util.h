#pragma once
// Helpers of the tests that use the tracer layer (raylab_tests_tracer and above).
#include <algorithm>
#include <vector>

#include "accel/accelerator.h"
#include "scenes/scene.h"
#include "tracer/camera.h"

namespace raylab::test {

// Fraction of an n x n grid of the scene's camera rays (pixel centres) that
// hit it: whether the default view looks at the scene.
inline double camera_hit_fraction(const Scene& s, const Accelerator& accel, int n = 24) {
  View v = s.view;
  v.width = v.height = n;
  const PinholeCamera cam(v);
  std::vector<Ray> rays;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) rays.push_back(cam.generate(x + 0.5f, y + 0.5f));
  std::vector<Hit> hits(rays.size());
  accel.intersect(rays, hits);
  return static_cast<double>(std::count_if(hits.begin(), hits.end(), [](const Hit& h) { return h.valid(); })) /
         static_cast<double>(hits.size());
}

}  // namespace raylab::test
