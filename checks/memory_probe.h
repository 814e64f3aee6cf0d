#pragma once
// A structure's build peak measured on a piece of the scene it is about to
// be built on. The registry's figure (bytes per triangle, measured once on a
// random soup) is a poor guide at scale: a k-d tree on a height field needs
// about 120 bytes per triangle where the soup's overlapping triangles make it
// 230, and the loose octree needs more on a terrain than on a soup. So before
// building on a large scene, the memory guard (checks/memory_guard.h) builds
// the structure on two contiguous pieces of the scene (the triangles around
// one point, at the scene's own density and triangle sizes) and takes the
// growth of the peak resident set from the smaller to the larger piece per
// triangle: what each further triangle costs, without the fixed costs (thread
// pools, per-thread buffers, huge-page rounding) that make a small build look
// 30 % dearer per triangle than a large one.
#include <cstddef>
#include <string>

#include "base/triangle_mesh.h"

namespace raylab {

// Triangles of the larger piece the probe builds on (the smaller has a
// quarter): at least this many, and at least 1/kProbeFraction of the scene.
// Some structures need less per triangle as scenes grow (the k-d tree 162
// bytes on terrain:n=707, 116 on terrain:n=2236, as its trees stop earlier),
// so the piece is kept within a factor kProbeFraction of the scene.
inline constexpr size_t kProbeTriangles = size_t{1} << 19;
inline constexpr size_t kProbeFraction = 32;
// Scenes with fewer triangles than this use the registry's figure (a probe
// would cost a noticeable share of their build, and they fit anyway).
inline constexpr size_t kProbeFromTriangles = size_t{4} << 20;
// The probe's figure is multiplied by this: the peaks vary with the
// allocator's reuse, and deeper trees may hold a little more per triangle
// (measured at 10^7 and 10^8 triangles they held less: bvh 166 bytes per
// triangle on terrain:n=707, 155 from the probe's difference, 152 at 10^8).
inline constexpr double kProbeSafety = 1.1;

// About `count` triangles of `mesh` whose centroids lie in the smallest cube
// around the median centroid (of a sample) that holds that many: a
// contiguous piece at the scene's own density. The whole mesh when it has no
// more than `count` triangles.
TriangleMesh mesh_piece(const TriangleMesh& mesh, size_t count);

struct BuildProbe {
  bool measured = false;          // false: the OS gives no peak (no /proc/self/clear_refs)
  size_t triangles = 0;           // of the larger piece
  double bytes_per_triangle = 0;  // the peak's growth per triangle between the two pieces
};

// The peak resident growth of building `accel_spec` on `piece` (VmHWM reset
// before the build; memory freed earlier is first returned to the OS, so the
// growth is the build's own); 0 where the OS gives no peak.
size_t build_peak_growth(const std::string& accel_spec, const TriangleMesh& piece);

// Builds `accel_spec` on a piece of a quarter of `count` triangles (once
// unmeasured, to set up what a first build sets up, then measured), then on
// mesh_piece(mesh, count), and returns the difference of their peak growths
// per triangle (the larger piece's own figure if the difference is not positive).
BuildProbe probe_build_peak(const std::string& accel_spec, const TriangleMesh& mesh, size_t count);

// The larger piece's size for a scene of `triangles`.
inline size_t probe_triangles(size_t triangles) {
  return triangles / kProbeFraction > kProbeTriangles ? triangles / kProbeFraction : kProbeTriangles;
}

}  // namespace raylab
