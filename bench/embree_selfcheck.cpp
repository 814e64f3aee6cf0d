#include "bench/embree_selfcheck.h"

#include <cstring>

#include <fmt/format.h>

#include "accel/embree/embree_accel.h"
#include "accel/registry.h"
#include "base/timer.h"
#include "tracer/trace.h"

namespace raylab {

namespace {

double median(std::vector<double> v) { return summarize_times(std::move(v)).median_s; }

SelfCheckRow check_set(const Scene& scene, const Accelerator& embree, const RaySet& set, int repeats) {
  SelfCheckRow row;
  row.scene = scene.name;
  row.ray_set = set.name;
  row.rays = set.rays.size();
  const PreparedSet prep = prepare_set(embree, set);
  row.prepare_ms = prep.prepare_s * 1e3;
  const size_t n = set.rays.size();
  TraceOutput adapter;
  std::vector<Hit> direct_hits(set.occlusion ? 0 : n);
  std::vector<uint8_t> direct_occ(set.occlusion ? n : 0);
  auto run_adapter = [&] { trace_set(embree, set, 1, adapter, nullptr, prep.rays.get()); };
  auto run_direct = [&] {
    if (set.occlusion) embree_direct_occluded(embree, *prep.rays, direct_occ);
    else embree_direct_intersect(embree, *prep.rays, direct_hits);
  };
  run_adapter();  // warm-up of both
  run_direct();
  row.identical = set.occlusion ? adapter.occluded == direct_occ
                                : std::memcmp(adapter.hits.data(), direct_hits.data(), n * sizeof(Hit)) == 0;
  std::vector<double> ta, td;
  for (int i = 0; i < std::max(1, repeats); ++i) {
    {
      ThreadCpuTimer t;
      run_adapter();
      ta.push_back(t.seconds());
    }
    {
      ThreadCpuTimer t;
      run_direct();
      td.push_back(t.seconds());
    }
  }
  const double a = median(ta), d = median(td);
  row.adapter_mrays_per_s = a > 0 ? n / a * 1e-6 : 0;
  row.direct_mrays_per_s = d > 0 ? n / d * 1e-6 : 0;
  row.ratio = row.direct_mrays_per_s > 0 ? row.adapter_mrays_per_s / row.direct_mrays_per_s : 0;
  return row;
}

}  // namespace

std::vector<SelfCheckRow> embree_selfcheck_sets(const Scene& scene, const std::vector<RaySet>& sets, int repeats,
                                                const std::string& embree_spec) {
  auto embree = make_accelerator(embree_spec);
  embree->build(scene.mesh);
  std::vector<SelfCheckRow> rows;
  for (const auto& set : sets) rows.push_back(check_set(scene, *embree, set, repeats));
  return rows;
}

std::vector<SelfCheckRow> embree_selfcheck(const Scene& scene, const std::vector<std::string>& ray_sets,
                                           const RaySetOptions& options, int repeats, const std::string& embree_spec) {
  auto reference = make_accelerator(embree_spec);
  reference->build(scene.mesh);
  const std::vector<RaySet> sets = make_ray_sets(scene, ray_sets, *reference, options);
  std::vector<SelfCheckRow> rows;
  for (const auto& set : sets) rows.push_back(check_set(scene, *reference, set, repeats));
  return rows;
}

std::string format_selfcheck_table(const std::vector<SelfCheckRow>& rows) {
  std::string s = fmt::format("{:<24} {:<8} {:>8} {:>10} {:>10} {:>14} {:>9} {:>9}\n", "scene", "rays", "count",
                              "adapter", "direct", "adapter/direct", "identical", "prep ms");
  for (const auto& r : rows)
    s += fmt::format("{:<24} {:<8} {:>8} {:>10.2f} {:>10.2f} {:>14.3f} {:>9} {:>9.2f}\n",
                     r.scene.size() > 24 ? r.scene.substr(r.scene.size() - 24) : r.scene, r.ray_set, r.rays, r.adapter_mrays_per_s,
                     r.direct_mrays_per_s, r.ratio, r.identical ? "yes" : "NO", r.prepare_ms);
  return s;
}

}  // namespace raylab
