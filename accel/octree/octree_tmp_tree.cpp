#include "accel/octree/octree_tmp_tree.h"

#include <stdexcept>
#include <utility>

#include <fmt/format.h>

namespace raylab {

void check_octree_triangle_count(size_t triangles, const char* what) {
  if (triangles > UINT32_MAX) throw std::length_error(fmt::format("{}: more than 2^32 triangles", what));
}

void flatten_octree(const OctTmpNode& root, OctreeTree& tree, const char* what) {
  std::vector<std::pair<const OctTmpNode*, uint32_t>> stack{{&root, 0u}};
  tree.nodes.assign(1, OctreeNode{});
  while (!stack.empty()) {
    const auto [tmp, index] = stack.back();
    stack.pop_back();
    if (tmp->refs.size() > kOctMaxNodeRefs)
      throw std::length_error(
          fmt::format("{}: a node holds {} triangles, at most {} supported", what, tmp->refs.size(), kOctMaxNodeRefs));
    if (tree.refs.size() + tmp->refs.size() > UINT32_MAX)
      throw std::length_error(fmt::format("{}: more than 2^32 triangle references", what));
    OctreeNode n;
    n.first_ref = static_cast<uint32_t>(tree.refs.size());
    tree.refs.insert(tree.refs.end(), tmp->refs.begin(), tmp->refs.end());
    uint32_t mask = 0;
    if (tmp->kids) {
      if (tree.nodes.size() + 8 > UINT32_MAX) throw std::length_error(fmt::format("{}: more than 2^32 nodes", what));
      n.first_child = static_cast<uint32_t>(tree.nodes.size());
      tree.nodes.resize(tree.nodes.size() + 8);
      for (uint32_t ch = 0; ch < 8; ++ch)
        if ((*tmp->kids)[ch].nonempty) mask |= 1u << ch;
      for (uint32_t ch = 8; ch-- > 0;) stack.emplace_back(&(*tmp->kids)[ch], n.first_child + ch);
    }
    n.meta = OctreeNode::make_meta(static_cast<uint32_t>(tmp->refs.size()), mask);
    tree.nodes[index] = n;
  }
}

}  // namespace raylab
