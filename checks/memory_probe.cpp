#include "checks/memory_probe.h"

#include <malloc.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <vector>

#include "accel/registry.h"
#include "base/pcg.h"
#include "checks/process_memory.h"

namespace raylab {

namespace {

Vec3f centroid(const TriangleMesh& m, size_t t) { return (m.vertex(t, 0) + m.vertex(t, 1) + m.vertex(t, 2)) / 3.0f; }

// Max-norm distance, the cube's "radius".
float cube_distance(const Vec3f& a, const Vec3f& b) { return (a - b).cwiseAbs().maxCoeff(); }

}  // namespace

TriangleMesh mesh_piece(const TriangleMesh& mesh, size_t count) {
  const size_t n = mesh.num_triangles();
  if (n <= count) return mesh;
  // A sample of centroids: their per-axis median is the piece's centre, and
  // the count/n quantile of their distances to it the cube's half-size.
  constexpr size_t kSample = 65536;
  Pcg32 rng(0x9E3779B97F4A7C15ull, 0x5A3B1E);
  std::vector<Vec3f> sample(std::min(kSample, n));
  for (auto& c : sample) c = centroid(mesh, std::min(n - 1, static_cast<size_t>(rng.uniform() * static_cast<double>(n))));
  Vec3f center;
  for (int a = 0; a < 3; ++a) {
    std::vector<float> v(sample.size());
    for (size_t i = 0; i < v.size(); ++i) v[i] = sample[i][a];
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    center[a] = v[v.size() / 2];
  }
  std::vector<float> dist(sample.size());
  for (size_t i = 0; i < dist.size(); ++i) dist[i] = cube_distance(sample[i], center);
  const size_t q = std::min(dist.size() - 1, static_cast<size_t>(std::ceil(static_cast<double>(count) / n * dist.size())));
  std::nth_element(dist.begin(), dist.begin() + static_cast<std::ptrdiff_t>(q), dist.end());
  const float radius = dist[q];

  TriangleMesh piece;
  std::unordered_map<uint32_t, uint32_t> remap;
  auto vertex_id = [&](uint32_t v) {
    const auto [it, added] = remap.emplace(v, static_cast<uint32_t>(piece.vertices.size()));
    if (added) piece.vertices.push_back(mesh.vertices[v]);
    return it->second;
  };
  for (size_t t = 0; t < n && piece.num_triangles() < 2 * count; ++t) {
    if (cube_distance(centroid(mesh, t), center) > radius) continue;
    const auto& tri = mesh.triangles[t];
    piece.triangles.push_back({vertex_id(tri[0]), vertex_id(tri[1]), vertex_id(tri[2])});
  }
  return piece;
}

size_t build_peak_growth(const std::string& accel_spec, const TriangleMesh& piece) {
  auto accel = make_accelerator(accel_spec);
  // Memory freed earlier and kept by the allocator would be reused without
  // growing the resident set: returned to the OS first.
  malloc_trim(0);
  if (!reset_peak_resident()) return 0;
  const size_t before = resident_bytes();
  accel->build(piece);
  const size_t peak = peak_resident_bytes();
  return peak > before ? peak - before : 0;
}

BuildProbe probe_build_peak(const std::string& accel_spec, const TriangleMesh& mesh, size_t count) {
  BuildProbe probe;
  // A first build of the smaller piece, not measured, sets up what a
  // structure sets up once (thread pools, per-thread scratch), so that
  // neither measured build pays for it.
  const TriangleMesh small = mesh_piece(mesh, count / 4);
  build_peak_growth(accel_spec, small);
  const size_t small_growth = build_peak_growth(accel_spec, small);
  const TriangleMesh large = mesh_piece(mesh, count);
  const size_t large_growth = build_peak_growth(accel_spec, large);
  probe.triangles = large.num_triangles();
  if (large_growth == 0 || large.num_triangles() <= small.num_triangles()) return probe;
  probe.measured = true;
  probe.bytes_per_triangle =
      large_growth > small_growth
          ? static_cast<double>(large_growth - small_growth) / static_cast<double>(large.num_triangles() - small.num_triangles())
          : static_cast<double>(large_growth) / static_cast<double>(large.num_triangles());
  return probe;
}

}  // namespace raylab
