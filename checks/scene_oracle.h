#pragma once
// The exact oracle as stress and verify ask it, one scene at a time: the
// loop over every triangle (checks/oracle.h) on small meshes; from
// kOracleIndexMinTriangles on, the culled search over an OracleIndex
// (checks/oracle_index.h), built on the first question (most runs never ask
// one) when the memory guard finds room for it, else the loop.
#include <cstddef>
#include <memory>
#include <mutex>

#include "base/ray.h"
#include "base/triangle_mesh.h"
#include "checks/memory_guard.h"
#include "checks/oracle.h"
#include "checks/oracle_index.h"

namespace raylab {

// Where the index pays off: its build costs about as much as 5 calls of the
// loop over every triangle, and each call then tests a small share of them.
inline constexpr size_t kOracleIndexMinTriangles = 20000;

// Building and holding the index beside everything already resident.
MemoryStep oracle_index_step(size_t triangles);

class SceneOracle {
 public:
  explicit SceneOracle(const TriangleMesh& mesh) : mesh_(mesh) {}

  // oracle_closest_hit(mesh, ray); safe to call from several threads.
  OracleHit closest_hit(const Ray& ray) const;

 private:
  const OracleIndex* index() const;

  const TriangleMesh& mesh_;
  mutable std::once_flag built_;
  mutable std::unique_ptr<OracleIndex> index_;
};

}  // namespace raylab
