// Microbenchmarks of the inner kernels (Google Benchmark): ray-triangle
// (watertight against Moller-Trumbore), the ray-box slab test, one 3D-DDA
// step and one 8-wide BVH node visit. `make microbench` runs them.
//
// Every benchmark cycles through a fixed pool of random inputs (seeded), so
// branch outcomes are realistic rather than one repeated case; the pools are
// small enough to stay in L1/L2, so memory latency is not part of the figure.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "accel/bvh/bvh_wide_node.h"
#include "accel/bvh/traverse_wide.h"
#include "accel/core/intersect_triangle.h"
#include "accel/core/slab_test.h"
#include "accel/core/grid/dda.h"
#include "accel/core/grid/dda_grid.h"
#include "base/pcg.h"

namespace raylab {
namespace {

constexpr size_t kPool = 1024;  // inputs per pool (power of two)

Vec3f random_point(Pcg32& rng, float lo, float hi) {
  return Vec3f(lo + (hi - lo) * rng.uniform(), lo + (hi - lo) * rng.uniform(), lo + (hi - lo) * rng.uniform());
}

Vec3f random_dir(Pcg32& rng) {
  while (true) {
    const Vec3f v = random_point(rng, -1.0f, 1.0f);
    const float n2 = v.squaredNorm();
    if (n2 > 1e-4f && n2 <= 1.0f) return v / std::sqrt(n2);
  }
}

// Rays from outside the unit cube aimed at a random point inside it.
std::vector<Ray> ray_pool(uint64_t seed) {
  Pcg32 rng(seed, 1);
  std::vector<Ray> rays;
  for (size_t i = 0; i < kPool; ++i) {
    const Vec3f target = random_point(rng, 0.0f, 1.0f);
    const Vec3f org = target - 3.0f * random_dir(rng);
    rays.emplace_back(org, (target - org).normalized());
  }
  return rays;
}

// Triangles around the middle of the cube: about half the rays hit each one.
struct Tri {
  Vec3f p0, p1, p2;
};
std::vector<Tri> triangle_pool(uint64_t seed) {
  Pcg32 rng(seed, 1);
  std::vector<Tri> tris;
  for (size_t i = 0; i < kPool; ++i) {
    const Vec3f c = random_point(rng, 0.3f, 0.7f);
    tris.push_back({c + 0.6f * random_dir(rng), c + 0.6f * random_dir(rng), c + 0.6f * random_dir(rng)});
  }
  return tris;
}

// One triangle test per iteration: ray k of the pool against triangle 7k;
// `test(k, triangle, t, u, v)` says whether it hit.
template <class Test>
void time_triangle_test(benchmark::State& state, Test test) {
  const auto tris = triangle_pool(2);
  size_t i = 0, hits = 0;
  for (auto _ : state) {
    const size_t k = i++ & (kPool - 1);
    const Tri& t = tris[(k * 7) & (kPool - 1)];
    float tt = 0.0f, u = 0.0f, v = 0.0f;
    hits += test(k, t, tt, u, v);
    benchmark::DoNotOptimize(tt);
  }
  state.counters["hit_rate"] = static_cast<double>(hits) / static_cast<double>(std::max<size_t>(i, 1));
}

void BM_TriangleWatertight(benchmark::State& state) {
  const auto rays = ray_pool(1);
  std::vector<WatertightRay> pre;
  for (const auto& r : rays) pre.emplace_back(r);
  time_triangle_test(state, [&](size_t k, const Tri& t, float& tt, float& u, float& v) {
    return intersect_watertight(pre[k], t.p0, t.p1, t.p2, 0.0f, 1e30f, tt, u, v);
  });
}
BENCHMARK(BM_TriangleWatertight);

// The same, with the per-ray setup (axis choice and shear) in the loop: what
// a single ray against a single triangle costs.
void BM_TriangleWatertightWithSetup(benchmark::State& state) {
  const auto rays = ray_pool(1);
  time_triangle_test(state, [&](size_t k, const Tri& t, float& tt, float& u, float& v) {
    const WatertightRay w(rays[k]);
    return intersect_watertight(w, t.p0, t.p1, t.p2, 0.0f, 1e30f, tt, u, v);
  });
}
BENCHMARK(BM_TriangleWatertightWithSetup);

void BM_TriangleMollerTrumbore(benchmark::State& state) {
  const auto rays = ray_pool(1);
  time_triangle_test(state, [&](size_t k, const Tri& t, float& tt, float& u, float& v) {
    return intersect_moller_trumbore(rays[k], t.p0, t.p1, t.p2, 0.0f, 1e30f, tt, u, v);
  });
}
BENCHMARK(BM_TriangleMollerTrumbore);

void BM_SlabTest(benchmark::State& state) {
  const auto rays = ray_pool(3);
  std::vector<SlabRay> pre;
  for (const auto& r : rays) pre.emplace_back(r);
  Pcg32 rng(4, 1);
  std::vector<Aabb> boxes;
  for (size_t i = 0; i < kPool; ++i) {
    const Vec3f a = random_point(rng, 0.0f, 1.0f), b = random_point(rng, 0.0f, 1.0f);
    boxes.emplace_back(a.cwiseMin(b), a.cwiseMax(b));
  }
  size_t i = 0, hits = 0;
  for (auto _ : state) {
    const size_t k = i++ & (kPool - 1);
    float t_entry = 0.0f;
    hits += slab_test(pre[k], boxes[(k * 13) & (kPool - 1)], 0.0f, 1e30f, t_entry);
    benchmark::DoNotOptimize(t_entry);
  }
  state.counters["hit_rate"] = static_cast<double>(hits) / static_cast<double>(std::max<size_t>(i, 1));
}
BENCHMARK(BM_SlabTest);

// One 3D-DDA step: whole walks through a res^3 grid over the unit cube,
// reported per cell visited (items_per_second = steps per second).
void BM_DdaStep(benchmark::State& state) {
  const int res = static_cast<int>(state.range(0));
  const DdaGrid g = make_dda_grid(Vec3d(0, 0, 0), Vec3d(1, 1, 1), GridRes{res, res, res});
  std::vector<DdaRay> rays;
  for (const auto& r : ray_pool(5)) rays.emplace_back(r);
  size_t i = 0;
  int64_t steps = 0;
  for (auto _ : state) {
    const DdaRay& r = rays[i++ & (kPool - 1)];
    double t0 = 0.0, t1 = 1e30;
    if (!dda_clip(r, g.lo, g.hi, t0, t1)) continue;
    int64_t sum = 0;
    dda_walk(g, r, t0, t1, [&](int64_t index, double, double) {
      sum += index;
      ++steps;
      return false;
    });
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(steps);
  state.counters["cells_per_walk"] = static_cast<double>(steps) / static_cast<double>(std::max<size_t>(i, 1));
}
BENCHMARK(BM_DdaStep)->Arg(16)->Arg(64);

// One visit of an 8-wide BVH node: the eight child-box slab tests in SIMD
// (the kernel the bvh accelerator runs at each inner node).
void BM_BvhNodeVisit(benchmark::State& state) {
  constexpr int N = 8;
  const auto rays = ray_pool(6);
  std::vector<WideNodeRay<N>> pre(kPool);
  for (size_t k = 0; k < kPool; ++k) init_node_ray(pre[k], rays[k], ray_is_axis_parallel(rays[k]));
  Pcg32 rng(7, 1);
  std::vector<WideNode<N>> nodes(64);
  for (auto& node : nodes)
    for (int c = 0; c < N; ++c) {
      const Vec3f a = random_point(rng, 0.0f, 1.0f), b = random_point(rng, 0.0f, 1.0f);
      const Vec3f lo = a.cwiseMin(b), hi = a.cwiseMax(b);
      for (int ax = 0; ax < 3; ++ax) {
        node.bounds[2 * ax][c] = lo[ax];
        node.bounds[2 * ax + 1][c] = hi[ax];
      }
      node.child[c] = 0;
    }
  using V = simd::vfloat<N>;
  const V tmin = V::broadcast(0.0f), tmax = V::broadcast(1e30f);
  size_t i = 0;
  uint64_t children = 0;
  for (auto _ : state) {
    const size_t k = i++ & (kPool - 1);
    V tnear;
    const uint32_t mask = intersect_children<N, false>(nodes[k & 63], pre[k], tmin, tmax, tnear);
    children += static_cast<uint64_t>(__builtin_popcount(mask));
    benchmark::DoNotOptimize(tnear);
  }
  state.counters["children_hit"] = static_cast<double>(children) / static_cast<double>(std::max<size_t>(i, 1));
}
BENCHMARK(BM_BvhNodeVisit);

}  // namespace
}  // namespace raylab
