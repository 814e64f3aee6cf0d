#pragma once
// Loose octree walk. Loose boxes of siblings overlap, so the walk cannot
// cut a node's interval by its dividing planes as the regular octree's
// parametric walk does: each existing child's loose box is clipped against
// the ray (the conservative slab test of Ize 2013, accel/core/slab_test.h),
// and the children it meets are walked in order of their entry distance,
// front to back. A node's own triangles are tested when it is entered.
// Closest hit: a node is entered only if its box begins before the closest
// hit so far; every triangle lies inside the loose box of its node, so no
// skipped node can hold a closer hit. Occlusion stops at the first hit.
// Node lists: SIMD triangle blocks by default (the octree's,
// accel/octree/octree_leaf_blocks.h), `simd=0` and tri=mt test the same
// lists one triangle at a time (same hits, bit for bit).
#include <cstdint>
#include <type_traits>

#include "accel/core/hit_recorder.h"
#include "accel/core/leaf_triangle.h"
#include "accel/core/slab_test.h"
#include "accel/loose_octree/loose_box.h"
#include "accel/octree/octree_leaf_blocks.h"
#include "accel/octree/octree_node.h"

namespace raylab {

struct LooseOctreeView {
  const OctreeNode* nodes = nullptr;
  LooseBoxes boxes;
  const LeafTriangle* tris = nullptr;  // in the order the nodes refer to them (one reference each)
  bool empty = true;
  // SIMD node lists (simd=1, watertight): a node's first_ref is then its first block.
  const OctTriangleBlock* blocks = nullptr;
};

// kBlocks: node lists are SIMD triangle blocks (watertight test only).
template <TriangleTest kTest, bool kAnyHit, bool kCount, bool kBlocks>
inline Hit traverse_loose_octree(const LooseOctreeView& tree, const Ray& ray, TraversalStats* stats) {
  HitRecorder<kAnyHit, kCount> rec(ray, stats);
  if (tree.empty || !ray_is_valid(ray)) return rec.hit();
  const SlabRay sr(ray);
  struct Entry {
    uint32_t node;
    uint32_t lattice[3];
    int level;
    float t;
  };
  float lo[3], hi[3], t_enter, t_exit;
  const uint32_t origin[3] = {0, 0, 0};
  tree.boxes.box(0, origin, lo, hi);
  rec.count_nodes(1);
  if (!clip_to_box(sr, lo, hi, ray.tmin, ray.tmax, t_enter, t_exit)) return rec.hit();
  static_assert(!kBlocks || kTest == TriangleTest::Watertight, "the SIMD lists run the watertight test");
  using ListRay = std::conditional_t<kBlocks, BlockRay<kOctBlockWidth>, TrianglePrecompute<kTest>>;
  const ListRay pre(ray);
  Entry stack[7 * (kOctMaxLevel + 1) + 1];
  int sp = 0;
  Entry cur{0, {0, 0, 0}, 0, t_enter};
  while (true) {
    const OctreeNode& n = tree.nodes[cur.node];
    if (n.mask()) rec.count_step();
    if (n.count() || !n.mask()) rec.count_leaf(n.count());
    if (const uint32_t count = n.count()) {
      bool kept;
      if constexpr (kBlocks)
        kept = intersect_block_leaf<kOctBlockWidth>(tree.blocks + n.first_ref, oct_node_blocks(count), pre, ray.tmin,
                                                    rec);
      else
        kept = intersect_leaf(pre, ray, tree.tris + n.first_ref, count, rec);
      if constexpr (kAnyHit) {
        if (kept) return rec.hit();
      }
    }
    if (const uint32_t mask = n.mask()) {
      const uint32_t half = OctreeCube::span(cur.level + 1);
      Entry kids[8];
      int count = 0;
      for (uint32_t c = 0; c < 8; ++c) {
        if (!(mask >> c & 1u)) continue;
        Entry e{n.first_child + c,
                {cur.lattice[0] + ((c & 1u) ? half : 0u), cur.lattice[1] + ((c & 2u) ? half : 0u),
                 cur.lattice[2] + ((c & 4u) ? half : 0u)},
                cur.level + 1,
                0.0f};
        tree.boxes.box(e.level, e.lattice, lo, hi);
        rec.count_nodes(1);
        if (!clip_to_box(sr, lo, hi, ray.tmin, rec.tmax(), e.t, t_exit)) continue;
        int i = count++;
        while (i > 0 && kids[i - 1].t < e.t) {  // descending: the nearest ends on top of the stack
          kids[i] = kids[i - 1];
          --i;
        }
        kids[i] = e;
      }
      for (int i = 0; i < count; ++i) stack[sp++] = kids[i];
    }
    while (true) {
      if (sp == 0) return rec.hit();
      const Entry& e = stack[--sp];
      if (e.t <= rec.tmax()) {
        cur = e;
        break;
      }
    }
  }
}

}  // namespace raylab
