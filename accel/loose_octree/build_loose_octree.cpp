#include "accel/loose_octree/build_loose_octree.h"

#include <array>
#include <memory>
#include <vector>

#include <tbb/parallel_for.h>

#include "accel/octree/octree_tmp_tree.h"

namespace raylab {

namespace {

constexpr size_t kParallelRefs = 2048;


class LooseBuilder {
 public:
  LooseBuilder(const LooseOctreeOptions& opt, const LooseBoxes& boxes, const std::vector<Aabb>& tri_boxes)
      : opt_(opt), boxes_(boxes), tri_boxes_(tri_boxes) {}

  void build(OctTmpNode& n, std::vector<uint32_t> ids, int level, const uint32_t c[3]) const {
    if (keep_as_leaf(n, ids, level, opt_.leaf, opt_.max_depth)) return;
    const uint32_t half = OctreeCube::span(level + 1);
    float mid[3];
    for (int k = 0; k < 3; ++k) mid[k] = boxes_.cube.plane(k, c[k] + half);
    std::array<std::vector<uint32_t>, 8> child_ids;
    float lo[8][3], hi[8][3];
    for (uint32_t ch = 0; ch < 8; ++ch) {
      const uint32_t cc[3] = {c[0] + ((ch & 1u) ? half : 0u), c[1] + ((ch & 2u) ? half : 0u),
                              c[2] + ((ch & 4u) ? half : 0u)};
      boxes_.box(level + 1, cc, lo[ch], hi[ch]);
    }
    for (const uint32_t id : ids) {
      const Aabb& b = tri_boxes_[id];
      const Vec3f centre = b.center();
      const uint32_t ch = (centre.x() >= mid[0] ? 1u : 0u) | (centre.y() >= mid[1] ? 2u : 0u) |
                          (centre.z() >= mid[2] ? 4u : 0u);
      bool fits = true;
      for (int k = 0; k < 3; ++k) fits = fits && b.lo[k] >= lo[ch][k] && b.hi[k] <= hi[ch][k];
      if (fits) child_ids[ch].push_back(id);
      else n.refs.push_back(id);
    }
    const size_t total = ids.size();
    std::vector<uint32_t>().swap(ids);
    n.kids = std::make_unique<std::array<OctTmpNode, 8>>();
    auto build_child = [&](uint32_t ch) {
      const uint32_t cc[3] = {c[0] + ((ch & 1u) ? half : 0u), c[1] + ((ch & 2u) ? half : 0u),
                              c[2] + ((ch & 4u) ? half : 0u)};
      build((*n.kids)[ch], std::move(child_ids[ch]), level + 1, cc);
    };
    if (total >= kParallelRefs) tbb::parallel_for(0u, 8u, [&](uint32_t ch) { build_child(ch); });
    else
      for (uint32_t ch = 0; ch < 8; ++ch) build_child(ch);
    n.nonempty = !n.refs.empty();
    bool any_child = false;
    for (const OctTmpNode& k : *n.kids) any_child = any_child || k.nonempty;
    n.nonempty = n.nonempty || any_child;
    if (!any_child) n.kids.reset();  // every triangle stayed: a leaf after all
  }

 private:
  LooseOctreeOptions opt_;
  const LooseBoxes& boxes_;
  const std::vector<Aabb>& tri_boxes_;
};


}  // namespace

OctreeTree build_loose_octree(const TriangleMesh& mesh, const LooseOctreeOptions& opt, LooseBoxes& boxes) {
  boxes.grow_per_unit = static_cast<float>(0.5 * (opt.looseness - 1.0));
  return build_octree_tree(mesh, opt.max_depth, "loose_octree",
                           [&](const OctreeCube& cube, const std::vector<Aabb>& tri_boxes, OctTmpNode& root,
                               std::vector<uint32_t> ids) {
                             boxes.cube = cube;
                             const uint32_t origin[3] = {0, 0, 0};
                             LooseBuilder(opt, boxes, tri_boxes).build(root, std::move(ids), 0, origin);
                           });
}

}  // namespace raylab
