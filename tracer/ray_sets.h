#pragma once
// Ray sets shared by verify and bench. Each set is generated once per scene
// and traced by every accelerator (Embree included), so every comparison is
// on the same rays.
//   primary  camera rays, one per pixel centre of the scene's view
//   random   incoherent segments between random points of the scene bounds
//            (enlarged by 5 % of the diagonal so flat scenes get volume)
//   diffuse  one cosine-distributed bounce from each primary hit, origin
//            offset along the normal
//   shadow   occlusion rays from primary hits to random points on emitters,
//            or to a point light above the scene when it has none
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "accel/accelerator.h"
#include "scenes/scene.h"

namespace raylab {

struct RaySet {
  std::string name;
  bool occlusion = false;  // traced with occluded() instead of intersect()
  std::vector<Ray> rays;
};

const std::vector<std::string>& ray_set_names();
// Throws SpecError naming the first unknown ray set and those that exist.
void check_ray_set_names(const std::vector<std::string>& names);

RaySet make_primary_rays(const Scene& scene, int width, int height);
// `count` rays at random positions on the image plane (for verify).
RaySet make_jittered_primary_rays(const Scene& scene, size_t count, uint64_t seed);
RaySet make_random_rays(const Scene& scene, size_t count, uint64_t seed);
RaySet make_diffuse_rays(const Scene& scene, const RaySet& primary, std::span<const Hit> hits, uint64_t seed);
RaySet make_shadow_rays(const Scene& scene, const RaySet& primary, std::span<const Hit> hits, uint64_t seed);

struct RaySetOptions {
  int width = 512, height = 512;  // primary rays (bench)
  size_t random_count = 262144;
  uint64_t seed = 1;
  bool jittered_primary = false;  // verify: random image positions instead of pixel centres
  size_t primary_count = 0;       // with jittered_primary
};

// Builds the named sets (any of ray_set_names()); diffuse and shadow rays
// start from primary hits computed with `reference`. Throws for unknown names.
std::vector<RaySet> make_ray_sets(const Scene& scene, const std::vector<std::string>& names,
                                  const Accelerator& reference, const RaySetOptions& options);

}  // namespace raylab
