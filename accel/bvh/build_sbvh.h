#pragma once
// Spatial-split BVH (Stich, Friedrich & Dietrich, "Spatial Splits in Bounding
// Volume Hierarchies", HPG 2009). At every node the best binned object split
// is computed; when its children overlap by more than alpha times the root's
// surface area, spatial splits are tried as well: the node is cut into
// uniform slabs along each axis, every reference is clipped into the slabs it
// spans, and a plane between slabs may send a straddling reference to both
// sides, each part's box clipped to the plane. Straddling references are
// "unsplit" (sent whole to one side) when that is cheaper (Stich et al. 4.3).
//
// Memory is bounded by a split budget: at most budget * n extra references
// are ever created; once it is spent the builder continues with object
// splits only. Parallel with TBB (large nodes bin in parallel, subtrees are tasks).
//
// The builder still works on boxes and centroids; the one primitive-specific
// operation, cutting a primitive by a plane, is a callback.
#include <span>

#include "accel/bvh/build_common.h"
#include "base/triangle_mesh.h"

namespace raylab {

// Cuts primitive `prim`, restricted to `box`, by the plane x[axis] = pos and
// returns the boxes of the parts on either side (each inside `box`, empty
// when that side holds nothing). With `conservative` the boxes must enclose
// the parts (round outward): they become the boxes of new references.
// Without it they only estimate split costs and may be off by rounding.
class PrimitiveSplitter {
 public:
  virtual ~PrimitiveSplitter() = default;
  virtual void split(uint32_t prim, const Aabb& box, int axis, float pos, bool conservative, Aabb& left,
                     Aabb& right) const = 0;
};

// Triangles: the polygon's vertices on each side plus its edges' crossings
// of the plane (conservative: computed in double, rounded outward to float).
class TriangleSplitter final : public PrimitiveSplitter {
 public:
  explicit TriangleSplitter(const TriangleMesh& mesh) : mesh_(mesh) {}
  void split(uint32_t prim, const Aabb& box, int axis, float pos, bool conservative, Aabb& left,
             Aabb& right) const override;

 private:
  const TriangleMesh& mesh_;
};

struct SbvhOptions {
  BuildOptions base;
  float alpha = 1e-5f;        // overlap threshold (fraction of the root's surface area)
  float split_budget = 0.5f;  // extra references allowed, as a fraction of the primitive count
  int spatial_bins = 32;      // slabs per axis for spatial splits
  // Spatial splits are only tried at nodes with at least this many
  // references: they pay off where large triangles straddle big nodes, and
  // trying them at every small node dominates build time.
  size_t min_spatial_refs = 0;
  // Whether spatial splits may cut axis-planar references (boxes thinner
  // than kAxisPlanarFraction of their largest extent along some axis: floors,
  // walls, ceilings of architectural scenes). On the interior views these
  // cuts are what spatial splits near the root do: camera rays test a
  // quarter to two thirds fewer boxes on the Sponza-based scenes, shadow rays
  // 4-46 % more, along their whole length (not only near the surfaces they
  // start on). Kept whole, such a reference goes to the side of its centroid
  // (measured over the interior views: docs/structures/bvh.md).
  bool split_planar = true;
};

// Fraction of a reference's largest box extent under which its smallest one
// makes it axis-planar (SbvhOptions::split_planar).
inline constexpr float kAxisPlanarFraction = 1.0f / 1024.0f;

struct SbvhStats {
  size_t references = 0;      // references in the final tree (>= primitives)
  size_t spatial_splits = 0;  // nodes split by a spatial split
};

BinaryBvh build_sbvh(std::span<const Aabb> boxes, std::span<const Vec3f> centroids,
                     const PrimitiveSplitter& splitter, const SbvhOptions& options, SbvhStats* stats = nullptr);

}  // namespace raylab
