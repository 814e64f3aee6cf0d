#include "accel/bvh/presplit.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "accel/bvh/build_sbvh.h"

namespace raylab {

namespace {

// The scene's dyadic grid: on each axis the planes lo + k * extent / 2^L.
struct DyadicGrid {
  double lo[3];
  double extent[3];
  double inv_extent[3];  // 0 on a flat axis

  // The coarsest grid plane strictly inside (blo, bhi) on `axis`: its level
  // L (1 = the middle plane) and position. False when none of levels 1..30
  // crosses the interval (a flat axis, or a piece finer than the grid).
  bool coarsest_plane(int axis, float blo, float bhi, int& level, float& pos) const {
    if (!(inv_extent[axis] > 0.0) || !(blo < bhi)) return false;
    constexpr double kScale = 2147483648.0;  // 2^31: 31-bit fixed point over the scene
    auto fixed = [&](float x) {
      const double u = std::clamp((static_cast<double>(x) - lo[axis]) * inv_extent[axis], 0.0, 1.0);
      return static_cast<uint32_t>(std::min(u * kScale, kScale - 1.0));
    };
    const uint32_t a = fixed(blo), b = fixed(bhi);
    if (a == b) return false;
    // The highest bit where the two differ is the coarsest level with a plane
    // between them; the plane is b with the bits below that one cleared.
    const int l = std::countl_zero(a ^ b);  // 1..31 (bit 31 is never set)
    if (l > 30) return false;
    const uint32_t plane = b & ~((uint32_t{1} << (31 - l)) - 1);
    pos = static_cast<float>(lo[axis] + static_cast<double>(plane) / kScale * extent[axis]);
    level = l;
    return blo < pos && pos < bhi;
  }

  // The split plane for a piece: the coarsest plane over the three axes,
  // the longer side of the box on a tie.
  bool choose(const Aabb& b, int& axis, float& pos, int& level) const {
    level = std::numeric_limits<int>::max();
    float best_extent = -1.0f;
    for (int a = 0; a < 3; ++a) {
      int l;
      float p;
      if (!coarsest_plane(a, b.lo[a], b.hi[a], l, p)) continue;
      const float e = b.hi[a] - b.lo[a];
      if (l < level || (l == level && e > best_extent)) {
        level = l;
        axis = a;
        pos = p;
        best_extent = e;
      }
    }
    return level != std::numeric_limits<int>::max();
  }
};

// x^(1/3) for x > 0 (normal floats): the exponent divided by three on the
// bits, then two Newton steps (relative error below 2e-6). libm's cbrtf was
// a third of the pass's time; a priority needs no more than this, and the
// same input gives the same bits on every machine.
inline float cube_root(float x) {
  if (!(x >= std::numeric_limits<float>::min())) return 0.0f;
  uint32_t u = std::bit_cast<uint32_t>(x);
  u = u / 3 + 709921077u;  // (127 - 127/3) << 23, rounded: a first guess within a few percent
  float y = std::bit_cast<float>(u);
  y = y - (y * y * y - x) / (3.0f * y * y);
  y = y - (y * y * y - x) / (3.0f * y * y);
  return y;
}

// Cuts triangle `tri` (the part inside `box`) with `splits` cuts and appends
// the pieces' references; returns how many were appended (at most splits + 1).
size_t cut(const TriangleSplitter& splitter, const DyadicGrid& grid, uint32_t tri, const Aabb& box, int splits,
           BuildRef* out) {
  int axis = 0, level = 0;
  float pos = 0.0f;
  if (splits == 0 || !grid.choose(box, axis, pos, level)) {
    *out = BuildRef::make(box, box.center(), tri);
    return 1;
  }
  Aabb left, right;
  splitter.split(tri, box, axis, pos, /*conservative=*/true, left, right);
  const bool has_left = !left.is_empty(), has_right = !right.is_empty();
  // Rounding can leave one side empty; the plane is then the other side's
  // boundary and is not chosen again.
  if (!has_left && !has_right) {
    *out = BuildRef::make(box, box.center(), tri);
    return 1;
  }
  if (!has_left || !has_right) return cut(splitter, grid, tri, has_left ? left : right, splits - 1, out);
  // The remaining cuts go to the pieces in proportion to their box areas.
  const double al = left.surface_area(), ar = right.surface_area();
  const int rest = splits - 1;
  const int to_left =
      al + ar > 0.0 ? static_cast<int>(std::lround(rest * (al / (al + ar)))) : rest / 2;
  const size_t nl = cut(splitter, grid, tri, left, to_left, out);
  return nl + cut(splitter, grid, tri, right, rest - to_left, out + nl);
}

// One reference per triangle, its whole box.
std::vector<BuildRef> whole_triangle_refs(const TriangleMesh& mesh) {
  const size_t n = mesh.num_triangles();
  std::vector<BuildRef> refs(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const Aabb b = mesh.triangle_bounds(i);
      refs[i] = BuildRef::make(b, b.center(), static_cast<uint32_t>(i));
    }
  });
  return refs;
}

}  // namespace

std::vector<BuildRef> presplit_references(const TriangleMesh& mesh, const PresplitOptions& options,
                                          PresplitStats* stats) {
  // Large fresh arrays cost page faults (a few milliseconds per ten
  // megabytes on a 2-core Xeon with AVX-512): the pass keeps
  // per-triangle arrays of at most eight bytes, recomputes the triangle boxes
  // instead of storing them, and writes the references where the builder
  // takes them.
  const size_t n = mesh.num_triangles();
  const size_t target = static_cast<size_t>(std::max(0.0, static_cast<double>(options.budget)) * static_cast<double>(n));
  if (stats) *stats = PresplitStats{};
  // No budget (the default build's path): the plain references, no more work.
  if (target == 0) return whole_triangle_refs(mesh);
  std::vector<int32_t> splits(n, 0);
  DyadicGrid grid{};
  const Aabb scene = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, n, 4096), Aabb::empty(),
      [&](const tbb::blocked_range<size_t>& r, Aabb acc) {
        for (size_t i = r.begin(); i < r.end(); ++i) acc.extend(mesh.triangle_bounds(i));
        return acc;
      },
      [](Aabb a, const Aabb& b) {
        a.extend(b);
        return a;
      });
  for (int a = 0; a < 3; ++a) {  // n > 0 here: the scene box is not empty
    grid.lo[a] = scene.lo[a];
    grid.extent[a] = static_cast<double>(scene.hi[a]) - scene.lo[a];
    grid.inv_extent[a] = grid.extent[a] > 0.0 ? 1.0 / grid.extent[a] : 0.0;
  }
  const float inv_scene_area = static_cast<float>(1.0 / std::max(static_cast<double>(scene.surface_area()), 1e-30));
  // Priorities (0 for triangles a cut cannot help). The excess first: it
  // rules out the triangles that fill their boxes before the grid is consulted.
  std::vector<float> priority(n, 0.0f);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const Aabb b = mesh.triangle_bounds(i);  // finite: the mesh is validated
      // A heuristic: float is plenty (cancellation only affects triangles
      // whose box is about their own size, which have nothing to gain).
      const Vec3f v0 = mesh.vertex(i, 0);
      const Vec3f nrm = (mesh.vertex(i, 1) - v0).cross(mesh.vertex(i, 2) - v0);
      // Areas as full surface areas: the box's, and twice the sum of the
      // triangle's three axis projections (|n| is twice its area).
      const float ideal = std::abs(nrm.x()) + std::abs(nrm.y()) + std::abs(nrm.z());
      const float excess = (b.surface_area() - ideal) * inv_scene_area;
      if (!(excess > 0.0f) || !std::isfinite(excess)) continue;
      int axis, level;
      float pos;
      if (!grid.choose(b, axis, pos, level)) continue;
      priority[i] = cube_root(std::ldexp(excess, -level));
    }
  });
  // The largest scale D whose splits floor(D * p), capped, fit the budget:
  // start from the estimate without the floors (a lower bound), widen until
  // the budget is exceeded, then bisect.
  double total = 0.0;
  for (const float x : priority) total += x;
  if (total > 0.0) {
    const float cap = static_cast<float>(std::max(0, options.max_splits));
    auto used = [&](const std::vector<float>& ps, double d) {
      const float df = static_cast<float>(d);
      int64_t acc = 0;
      for (const float x : ps) acc += static_cast<int32_t>(std::min(cap, df * x));
      return static_cast<size_t>(acc);
    };
    // Steps of 16: with many tiny priorities the floor-free estimate can be
    // orders of magnitude low.
    double lo = static_cast<double>(target) / total, hi = 16.0 * lo;
    for (int k = 0; k < 32 && used(priority, hi) <= target; ++k) lo = hi, hi *= 16.0;
    // Below hi only priorities of at least 1 / hi get a split: bisect on those
    // (at most the budget's count of them, a small part of a large mesh).
    std::vector<float> live;
    const float floor_p = static_cast<float>(1.0 / hi);
    for (const float x : priority)
      if (x >= floor_p) live.push_back(x);
    for (int k = 0; k < 20; ++k) {
      const double mid = std::sqrt(lo * hi);  // bisection of the ratio
      (used(live, mid) <= target ? lo : hi) = mid;
    }
    const float df = static_cast<float>(lo);
    for (size_t i = 0; i < n; ++i) splits[i] = static_cast<int32_t>(std::min(cap, df * priority[i]));
  }
  // Each triangle writes its pieces into its own range of slots (one slot
  // per split plus one); a cut that leaves one side empty leaves a slot
  // unused, and those gaps are closed afterwards, in order.
  size_t slots = n;
  for (size_t i = 0; i < n; ++i) slots += static_cast<size_t>(splits[i]);
  if (slots == n) return whole_triangle_refs(mesh);  // priorities too small for one split
  std::vector<BuildRef> refs(slots);
  std::vector<uint32_t> pieces(n, 1);
  std::vector<size_t> first(n);  // each triangle's first slot
  size_t at = 0;
  for (size_t i = 0; i < n; ++i) {
    first[i] = at;
    at += 1 + static_cast<size_t>(splits[i]);
  }
  const TriangleSplitter splitter(mesh);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const auto tri = static_cast<uint32_t>(i);
      const Aabb b = mesh.triangle_bounds(i);
      if (splits[i] == 0) refs[first[i]] = BuildRef::make(b, b.center(), tri);
      else pieces[i] = static_cast<uint32_t>(cut(splitter, grid, tri, b, splits[i], &refs[first[i]]));
    }
  });
  size_t m = 0;
  for (size_t i = 0; i < n; ++i) {
    if (m != first[i])
      for (uint32_t k = 0; k < pieces[i]; ++k) refs[m + k] = refs[first[i] + k];
    m += pieces[i];
  }
  refs.resize(m);
  if (stats)
    for (size_t i = 0; i < n; ++i) stats->triangles_split += pieces[i] > 1;
  return refs;
}

}  // namespace raylab
