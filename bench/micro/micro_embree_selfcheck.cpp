// The reference's self-check as a Google Benchmark (`make microbench`): the
// `embree` accelerator as `raylab bench` times it (trace_set on its prepared
// rays) against a plain rtcIntersect1 / rtcOccluded1 loop on the same
// prepared rays. The two figures of one ray set should agree within a few
// per cent; `raylab bench --embree-selfcheck` prints the ratio directly (and
// on the shared scenes' interior views).
#include <benchmark/benchmark.h>

#include <memory>

#include "accel/embree/embree_accel.h"
#include "accel/registry.h"
#include "bench/ray_sets.h"
#include "bench/trace.h"
#include "scenes/scene_registry.h"

namespace raylab {
namespace {

struct Fixture {
  Scene scene;
  std::unique_ptr<Accelerator> embree;
  std::vector<RaySet> sets;
  std::vector<PreparedSet> prepared;
};

const Fixture& fixture() {
  static const Fixture f = [] {
    Fixture x{load_scene("sphereflake:level=3"), nullptr, {}, {}};
    x.embree = make_accelerator("embree");
    x.embree->build(x.scene.mesh);
    RaySetOptions o;
    o.width = o.height = 256;
    o.random_count = 65536;
    x.sets = make_ray_sets(x.scene, ray_set_names(), *x.embree, o);
    for (const auto& s : x.sets) x.prepared.push_back(prepare_set(*x.embree, s));
    return x;
  }();
  return f;
}

void BM_EmbreeAdapter(benchmark::State& state) {
  const Fixture& f = fixture();
  const size_t s = static_cast<size_t>(state.range(0));
  TraceOutput out;
  for (auto _ : state) {
    trace_set(*f.embree, f.sets[s], 1, out, nullptr, f.prepared[s].rays.get());
    benchmark::ClobberMemory();
  }
  state.SetLabel(f.sets[s].name);
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * f.sets[s].rays.size()));
}

void BM_EmbreeDirectLoop(benchmark::State& state) {
  const Fixture& f = fixture();
  const size_t s = static_cast<size_t>(state.range(0));
  const RaySet& set = f.sets[s];
  std::vector<Hit> hits(set.rays.size());
  std::vector<uint8_t> occ(set.rays.size());
  for (auto _ : state) {
    if (set.occlusion) embree_direct_occluded(*f.embree, *f.prepared[s].rays, occ);
    else embree_direct_intersect(*f.embree, *f.prepared[s].rays, hits);
    benchmark::ClobberMemory();
  }
  state.SetLabel(set.name);
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * set.rays.size()));
}

// Arg: index into ray_set_names() (primary, diffuse, shadow, random).
BENCHMARK(BM_EmbreeAdapter)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_EmbreeDirectLoop)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace raylab
