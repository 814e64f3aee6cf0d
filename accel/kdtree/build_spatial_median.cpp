#include "accel/kdtree/build_spatial_median.h"

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include "accel/kdtree/kd_build_start.h"
#include "accel/core/clip_triangle.h"
#include "accel/kdtree/kd_tree_writer.h"

namespace raylab {

namespace {

// A triangle and the bounds of its part inside the current cell.
struct PrimRef {
  uint32_t tri;
  Aabb box;
};


class MedianBuilder : KdBuilderBase {
 public:
  using KdBuilderBase::KdBuilderBase;

  KdTree run() {
    return run_from_root(kKdMaxIndex, [&](const Aabb& bounds) {
      std::vector<PrimRef> refs(mesh_.num_triangles());
      for (size_t i = 0; i < refs.size(); ++i) refs[i] = PrimRef{static_cast<uint32_t>(i), tri_boxes_[i]};
      build(0, bounds, std::move(refs), 0);
    });
  }

 private:
  // Which side(s) of plane p on axis k the part `b` lies; the same rules as
  // the SAH builder's event classification (planar parts in the plane go left).
  static void sides(const Aabb& b, int k, float p, bool& left, bool& right) {
    if (b.lo[k] == b.hi[k]) {
      left = b.lo[k] <= p;
      right = !left;
    } else {
      left = b.lo[k] < p;
      right = b.hi[k] > p;
    }
  }

  void build(uint32_t node, const Aabb& cell, std::vector<PrimRef> refs, int depth) {
    const size_t n = refs.size();
    if (n <= static_cast<size_t>(opt_.median_leaf_size) || depth >= max_depth_) return make_leaf(node, refs);

    // Longest axis first; the next ones when the middle separates nothing.
    const Vec3f ext = cell.diagonal();
    int order[3] = {0, 1, 2};
    std::stable_sort(order, order + 3, [&](int x, int y) { return ext[x] > ext[y]; });
    int axis = -1;
    float split = 0.0f;
    for (const int k : order) {
      const float p = cell.lo[k] + 0.5f * (cell.hi[k] - cell.lo[k]);
      if (!(p > cell.lo[k] && p < cell.hi[k])) continue;  // zero (or one-ulp) extent
      size_t nl = 0, nr = 0;
      for (const PrimRef& r : refs) {
        bool l, rt;
        sides(r.box, k, p, l, rt);
        nl += l;
        nr += rt;
      }
      // Progress: at least one side loses a triangle, and less than half of
      // them straddle the plane. Without the second rule a cell of
      // overlapping or duplicated triangles next to a few small ones would
      // copy the overlapping ones into both children at every level
      // (exponential in depth); a few large triangles spanning a cell whose
      // other triangles all lie on one side do not stop the split.
      if ((nl < n || nr < n) && 2 * (nl + nr) < 3 * n) {
        axis = k;
        split = p;
        break;
      }
    }
    if (axis < 0) return make_leaf(node, refs);

    Aabb left_cell = cell, right_cell = cell;
    left_cell.hi[axis] = split;
    right_cell.lo[axis] = split;
    std::vector<PrimRef> left, right;
    for (const PrimRef& r : refs) {
      bool l, rt;
      sides(r.box, axis, split, l, rt);
      if (l && rt) {
        Aabb b;
        if (clip_to(r.tri, r.box, left_cell, b)) left.push_back(PrimRef{r.tri, b});
        if (clip_to(r.tri, r.box, right_cell, b)) right.push_back(PrimRef{r.tri, b});
      } else if (l) {
        left.push_back(r);
      } else {
        right.push_back(r);
      }
    }
    // A guard only: clipping removes references, so the rule above holds.
    if (left.size() >= n && right.size() >= n) return make_leaf(node, refs);
    std::vector<PrimRef>().swap(refs);

    const uint32_t pair = writer_.allocate_pair();
    writer_.set_inner(node, axis, split, pair);
    build_children(
        n, [&] { build(pair, left_cell, std::move(left), depth + 1); },
        [&] { build(pair + 1, right_cell, std::move(right), depth + 1); });
  }

  bool clip_to(uint32_t tri, const Aabb& part, const Aabb& cell, Aabb& out) const {
    if (!opt_.perfect_splits) return clip_box_to_cell(part, cell, out);
    return clip_triangle_to_cell(mesh_.vertex(tri, 0), mesh_.vertex(tri, 1), mesh_.vertex(tri, 2), cell, out);
  }

  void make_leaf(uint32_t node, const std::vector<PrimRef>& refs) {
    std::vector<uint32_t> prims(refs.size());
    for (size_t i = 0; i < refs.size(); ++i) prims[i] = refs[i].tri;
    std::sort(prims.begin(), prims.end());
    writer_.set_leaf(node, prims);
  }

};

}  // namespace

KdTree build_kdtree_median(const TriangleMesh& mesh, const KdBuildOptions& options) {
  return MedianBuilder(mesh, options).run();
}

}  // namespace raylab
