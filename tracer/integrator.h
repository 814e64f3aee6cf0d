#pragma once
// Unidirectional path tracer: next-event estimation to emissive triangles
// combined with cosine-weighted BSDF sampling by multiple importance sampling
// (Veach & Guibas 1995, power heuristic), Russian roulette after a few
// bounces. Diffuse and emissive materials only.
//
// Rays are traced in batches through the Accelerator interface: each tile's
// paths advance one bounce at a time (a small wavefront), so the virtual call
// is per batch and any accelerator spec can render. Every path owns a PCG32
// stream derived from (seed, pixel, sample) and each pixel sums its samples
// in sample order, so the same seed gives the same image bytes whatever the
// thread count.
#include <atomic>
#include <cstdint>

#include "accel/accelerator.h"
#include "scenes/scene.h"
#include "tracer/image.h"

namespace raylab {

struct RenderSettings {
  int width = 512;
  int height = 512;
  int spp = 16;
  int max_depth = 64;          // hard cap on bounces (Russian roulette ends most paths earlier)
  int rr_depth = 3;            // Russian roulette starts after this many bounces
  uint64_t seed = 1;
  bool progress = false;       // progress line on stderr for renders longer than a second
  // Ctrl-C: polled before every batch of paths; once set, the remaining work
  // is skipped and the result is marked incomplete.
  const std::atomic<bool>* stop = nullptr;
};

struct RenderResult {
  Image image;
  double seconds = 0.0;
  uint64_t rays = 0;           // closest-hit rays traced
  uint64_t shadow_rays = 0;    // occlusion rays traced
  bool complete = true;        // false when `stop` ended the render early (the image is partial)
};

RenderResult render(const Scene& scene, const Accelerator& accel, const RenderSettings& settings);

}  // namespace raylab
