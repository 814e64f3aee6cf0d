#pragma once
// The one accelerator interface. Dispatch is virtual per batch (a span of
// rays); every implementation runs a tight non-virtual loop inside.
//
// Contract:
//  - build() may be called once (a second call throws std::logic_error); the
//    mesh must outlive the accelerator. It validates the mesh, then times the
//    structure's own build_impl(): every structure's build_ms means the same.
//  - intersect()/occluded() are const and thread-safe: callers may trace
//    disjoint sub-spans from several threads at once. Tracing before
//    build() reports misses (Embree's adapter throws), never a crash.
//  - Invalid rays (see ray_is_valid) report a miss / not occluded.
//  - When `stats` is non-null the instrumented kernel runs and adds its
//    per-ray counters to *stats (the uninstrumented kernel does no counting).
//
// Optional per-batch preparation (timed = traversal only): a structure that
// traces rays in its own layout (Embree's RTCRayHit arrays and SOA packets,
// say) converts a whole ray set once in prepare(), outside any timed region;
// the benchmark reports that cost on its own (`prepare_ms`) and times only
// intersect_prepared()/occluded_prepared(). These receive the prepared object
// and the sub-range a thread traces: `rays` is rays_given_to_prepare[begin,
// begin + rays.size()) and results go to hits/occluded[0, rays.size()).
// A prepared object is read-only while tracing (several threads may trace
// disjoint sub-ranges at once) and is valid for the ray span it was made
// from. Structures without a preparation step return nullptr from prepare()
// and the *_prepared calls forward to intersect()/occluded(), so they behave
// exactly as without preparation. Results are identical with and without it.
#include <cstdint>
#include <map>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>

#include "accel/structure_outline.h"
#include "base/hit.h"
#include "base/ray.h"
#include "base/timer.h"
#include "base/triangle_mesh.h"

namespace raylab {

// Figures every structure reports after a build. Fields that do not apply
// stay at their defaults (0, or NaN for sah_cost).
struct BuildStats {
  double build_ms = 0.0;
  size_t bytes = 0;       // memory held by the structure (excluding the caller's mesh)
  size_t nodes = 0;       // nodes, or cells for grids
  size_t leaves = 0;      // leaves, or non-empty cells
  int max_depth = 0;
  double avg_depth = 0.0;  // mean leaf depth
  double sah_cost = std::numeric_limits<double>::quiet_NaN();
  // Structure-specific figures (references per triangle, empty fraction, ...).
  std::map<std::string, double> extra;
};

// Per-ray traversal counters accumulated by the instrumented kernels
// (HitRecorder, accel/core/hit_recorder.h), one definition for every
// structure: docs/json-reports.md, "Per-ray counters".
struct TraversalStats {
  uint64_t rays = 0;
  uint64_t nodes_visited = 0;   // bounds tested: a BVH's child boxes, a tree's nodes entered, grid cells entered
  uint64_t steps = 0;           // Havran's traversal steps: inner nodes visited, grid cells entered
  uint64_t leaves = 0;          // leaves or cells visited whose triangles were tested
  uint64_t empty_leaves = 0;    // leaves or cells visited that hold no triangle
  uint64_t triangle_tests = 0;

  // Everything but the rays: the work of an inner walk (a hybrid's cell
  // tree, the entry grid's second walk) added to the ray that made it.
  void add_walk(const TraversalStats& o) {
    nodes_visited += o.nodes_visited;
    steps += o.steps;
    leaves += o.leaves;
    empty_leaves += o.empty_leaves;
    triangle_tests += o.triangle_tests;
  }
  TraversalStats& operator+=(const TraversalStats& o) {
    rays += o.rays;
    add_walk(o);
    return *this;
  }
};

// A structure's own form of a ray set (see prepare()); opaque to callers.
struct PreparedRays {
  virtual ~PreparedRays() = default;
};

class Accelerator {
 public:
  virtual ~Accelerator() = default;

  // The spec string this accelerator was created from, e.g. "bvh:leaf=4".
  const std::string& spec() const { return spec_; }
  void set_spec(std::string s) { spec_ = std::move(s); }

  // Validates the mesh (MeshError), builds, and sets build_ms to the time
  // of build_impl().
  BuildStats build(const TriangleMesh& mesh) {
    if (built_) throw std::logic_error("accelerator " + spec_ + ": build() called twice");
    mesh.validate();
    built_ = true;
    const Timer timer;
    BuildStats s = build_impl(mesh);
    s.build_ms = timer.ms();
    return s;
  }

  // Closest hit for every ray: hits[i] receives the result of rays[i].
  virtual void intersect(std::span<const Ray> rays, std::span<Hit> hits,
                         TraversalStats* stats = nullptr) const = 0;

  // Any hit within [tmin, tmax]: occluded[i] = 1 when rays[i] hits something.
  virtual void occluded(std::span<const Ray> rays, std::span<uint8_t> occluded,
                        TraversalStats* stats = nullptr) const = 0;

  // Converts `rays` (all of a ray set) into this structure's layout, or
  // returns nullptr when it traces our Ray directly. `occlusion`: the set is
  // traced with occluded_prepared(), else with intersect_prepared().
  virtual std::unique_ptr<PreparedRays> prepare(std::span<const Ray> /*rays*/, bool /*occlusion*/) const {
    return nullptr;
  }

  // As intersect()/occluded(), on the sub-range [begin, begin + rays.size())
  // of the span given to prepare(). `prepared` may be null (nothing prepared).
  virtual void intersect_prepared(const PreparedRays* /*prepared*/, size_t /*begin*/, std::span<const Ray> rays,
                                  std::span<Hit> hits, TraversalStats* stats = nullptr) const {
    intersect(rays, hits, stats);
  }
  virtual void occluded_prepared(const PreparedRays* /*prepared*/, size_t /*begin*/, std::span<const Ray> rays,
                                 std::span<uint8_t> occluded, TraversalStats* stats = nullptr) const {
    this->occluded(rays, occluded, stats);
  }

  // Optional picture of the built structure (accel/structure_outline.h):
  // appends its boxes / split planes / cells of depth <= max_depth to `out`.
  // Structures that implement it say so with Capabilities::outline; the
  // default adds nothing. Never called on the hot path.
  virtual void outline(int /*max_depth*/, StructureOutline& /*out*/) const {}

  // Convenience single-ray queries (not for hot loops).
  Hit intersect1(const Ray& r) const {
    Hit h;
    intersect(std::span<const Ray>(&r, 1), std::span<Hit>(&h, 1));
    return h;
  }
  bool occluded1(const Ray& r) const {
    uint8_t o = 0;
    occluded(std::span<const Ray>(&r, 1), std::span<uint8_t>(&o, 1));
    return o != 0;
  }

 protected:
  // The structure's own build, on a validated mesh. build_ms is set by build().
  virtual BuildStats build_impl(const TriangleMesh& mesh) = 0;

 private:
  std::string spec_;
  bool built_ = false;
};

}  // namespace raylab
