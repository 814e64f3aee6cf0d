#include "checks/scene_oracle.h"

#include <tbb/task_arena.h>

namespace raylab {

MemoryStep oracle_index_step(size_t triangles) {
  MemoryStep s;
  s.what = "the oracle's index";
  s.bytes_per_unit = kOracleIndexBuildBytesPerTriangle;
  s.units = triangles;
  s.unit = "triangles";
  s.bytes = static_cast<size_t>(s.bytes_per_unit * static_cast<double>(triangles));
  s.basis = "its build's sort keys beside the index";
  return s;
}

const OracleIndex* SceneOracle::index() const {
  if (mesh_.num_triangles() < kOracleIndexMinTriangles || mesh_.num_triangles() >= OracleIndex::kMaxTriangles)
    return nullptr;
  std::call_once(built_, [this] {
    MemoryGuard guard;
    if (!guard.fits(oracle_index_step(mesh_.num_triangles()))) return;  // the loop: slow, but it fits
    // Isolated: while the build waits for its own parallel tasks, this thread
    // must not pick up another caller's ray, which would wait on the build.
    tbb::this_task_arena::isolate([this] { index_ = std::make_unique<OracleIndex>(mesh_); });
  });
  return index_.get();
}

OracleHit SceneOracle::closest_hit(const Ray& ray) const {
  if (const OracleIndex* idx = index()) return oracle_closest_hit(*idx, mesh_, ray);
  return oracle_closest_hit(mesh_, ray);
}

}  // namespace raylab
