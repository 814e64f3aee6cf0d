#include "accel/bvh/bvh_wide_node.h"

#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "accel/core/simd/leaf_blocks.h"

namespace raylab {

template <int N, int W>
WideBvh<N, W> make_wide_bvh(const WideTree& t, const TriangleMesh& mesh, bool edges) {
  WideBvh<N, W> out;
  const size_t leaves = t.leaf_count();
  std::vector<uint32_t> first_block(leaves + 1, 0);
  for (size_t i = 0; i < leaves; ++i) {
    const uint32_t blocks = (t.leaf_size(i) + W - 1) / W;
    if (blocks > wide_ref::kMaxBlocks) throw std::logic_error("wide bvh: leaf needs more than 15 blocks");
    first_block[i + 1] = first_block[i] + blocks;
  }
  if (first_block[leaves] > wide_ref::kFirstBlockMask) throw std::length_error("wide bvh: too many triangle blocks");
  out.blocks.resize(first_block[leaves]);
  const BlockVertices stored = edges ? BlockVertices::Edges : BlockVertices::Corners;
  tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves, 1024), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i)
      fill_leaf_blocks<W>(mesh, t.leaf_prims.data() + t.leaf_begin[i], static_cast<uint32_t>(t.leaf_size(i)),
                          out.blocks.data() + first_block[i], stored);
  });
  auto leaf_ref = [&](uint32_t leaf) {
    return wide_ref::leaf(first_block[leaf], first_block[leaf + 1] - first_block[leaf]);
  };
  out.root_box = t.root_box;
  if (t.root_leaf >= 0) {
    out.root_ref = leaves ? leaf_ref(0) : wide_ref::kEmpty;
    return out;
  }
  out.nodes.resize(t.nodes.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, t.nodes.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const WideTree::Node& src = t.nodes[i];
      if (src.count > N) throw std::logic_error("wide bvh: node has more children than the layout's width");
      WideNode<N>& dst = out.nodes[i];
      for (int c = 0; c < N; ++c) {
        if (c < src.count) {
          const WideTree::Child& ch = src.child[c];
          for (int a = 0; a < 3; ++a) {
            dst.bounds[2 * a][c] = ch.box.lo[a];
            dst.bounds[2 * a + 1][c] = ch.box.hi[a];
          }
          dst.child[c] = ch.leaf ? leaf_ref(ch.index) : ch.index;
        } else {
          for (int a = 0; a < 3; ++a) {
            dst.bounds[2 * a][c] = std::numeric_limits<float>::infinity();
            dst.bounds[2 * a + 1][c] = -std::numeric_limits<float>::infinity();
          }
          dst.child[c] = wide_ref::kEmpty;
        }
      }
    }
  });
  out.root_ref = 0;
  return out;
}

template WideBvh<4, 4> make_wide_bvh<4, 4>(const WideTree&, const TriangleMesh&, bool);
template WideBvh<4, 8> make_wide_bvh<4, 8>(const WideTree&, const TriangleMesh&, bool);
template WideBvh<4, 16> make_wide_bvh<4, 16>(const WideTree&, const TriangleMesh&, bool);
template WideBvh<8, 4> make_wide_bvh<8, 4>(const WideTree&, const TriangleMesh&, bool);
template WideBvh<8, 8> make_wide_bvh<8, 8>(const WideTree&, const TriangleMesh&, bool);
template WideBvh<8, 16> make_wide_bvh<8, 16>(const WideTree&, const TriangleMesh&, bool);
template WideBvh<16, 8> make_wide_bvh<16, 8>(const WideTree&, const TriangleMesh&, bool);

}  // namespace raylab
