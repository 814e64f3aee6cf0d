#include "accel/hybrid/cell_trees.h"

#include <algorithm>

#include <tbb/parallel_for.h>

#include "accel/bvh/build_binned_sah.h"
#include "accel/kdtree/build_sah_events.h"

namespace raylab {

namespace {

// The non-empty cells, in index order.
std::vector<uint32_t> occupied_cells(const TopGrid& g) {
  std::vector<uint32_t> cells;
  const auto& off = g.lists.offsets;
  for (size_t c = 0; c + 1 < off.size(); ++c)
    if (off[c + 1] > off[c]) cells.push_back(static_cast<uint32_t>(c));
  return cells;
}

void cell_coords(const DdaGrid& g, uint32_t cell, int32_t c[3]) {
  c[0] = static_cast<int32_t>(cell % static_cast<uint32_t>(g.res[0]));
  c[1] = static_cast<int32_t>((cell / static_cast<uint32_t>(g.res[0])) % static_cast<uint32_t>(g.res[1]));
  c[2] = static_cast<int32_t>(cell / (static_cast<uint64_t>(g.res[0]) * static_cast<uint32_t>(g.res[1])));
}

// One cell's tree before the arrays are joined.
template <typename Node>
struct CellPart {
  std::vector<Node> nodes;
  std::vector<LeafTriangle> tris;
  std::vector<uint32_t> ids;
  Aabb bounds;
};

// Joins the parts into the forest's arrays, then makes the views.
template <typename Node, typename View, typename MakeView>
void join_parts(const TopGrid& g, const std::vector<uint32_t>& cells, std::vector<CellPart<Node>>& parts,
                CellForest<Node, View>& f, MakeView&& make_view) {
  size_t nn = 0, nt = 0, ni = 0;
  for (const auto& p : parts) {
    nn += p.nodes.size();
    nt += p.tris.size();
    ni += p.ids.size();
  }
  f.nodes.reserve(nn);
  f.tris.reserve(nt);
  f.ids.reserve(ni);
  std::vector<size_t> node_at, tri_at, id_at;
  for (auto& p : parts) {
    node_at.push_back(f.nodes.size());
    tri_at.push_back(f.tris.size());
    id_at.push_back(f.ids.size());
    f.nodes.insert(f.nodes.end(), p.nodes.begin(), p.nodes.end());
    f.tris.insert(f.tris.end(), p.tris.begin(), p.tris.end());
    f.ids.insert(f.ids.end(), p.ids.begin(), p.ids.end());
  }
  f.cell_tree.assign(g.dda.cells(), kNoCellTree);
  for (size_t i = 0; i < parts.size(); ++i) {
    f.cell_tree[cells[i]] = static_cast<uint32_t>(f.views.size());
    f.views.push_back(make_view(f.nodes.data() + node_at[i], f.tris.data() + tri_at[i], f.ids.data() + id_at[i],
                                parts[i]));
  }
  f.totals.trees = parts.size();
  f.totals.bytes = f.nodes.size() * sizeof(Node) + f.tris.size() * sizeof(LeafTriangle) +
                   f.ids.size() * sizeof(uint32_t) + f.views.size() * sizeof(View) +
                   f.cell_tree.size() * sizeof(uint32_t);
}

// Every occupied cell's part, built in parallel: build_part(cell, part).
template <typename Node, typename BuildPart>
std::vector<CellPart<Node>> build_parts(const std::vector<uint32_t>& cells, BuildPart&& build_part) {
  std::vector<CellPart<Node>> parts(cells.size());
  tbb::parallel_for(size_t{0}, cells.size(), [&](size_t i) { build_part(cells[i], parts[i]); });
  return parts;
}

// One cell tree's shape added to the forest's totals.
template <typename Shape>
void add_to_totals(CellTreeTotals& t, const Shape& s, size_t references) {
  t.nodes += s.nodes;
  t.leaves += s.leaves;
  t.references += references;
  t.max_depth = std::max(t.max_depth, s.max_depth);
  t.leaf_depth_sum += s.avg_leaf_depth * static_cast<double>(s.leaves);
}

}  // namespace

CellBvhForest build_cell_bvhs(const TopGrid& g, int leaf) {
  CellBvhForest f;
  if (g.empty) return f;
  const std::vector<uint32_t> cells = occupied_cells(g);
  auto parts = build_parts<Bvh2Node>(cells, [&](uint32_t cell, CellPart<Bvh2Node>& p) {
    int32_t c[3];
    cell_coords(g.dda, cell, c);
    const Aabb cell_box = top_cell_box(g.dda, c[0], c[1], c[2]);
    const uint32_t begin = g.lists.offsets[cell], end = g.lists.offsets[cell + 1];
    std::vector<BuildRef> refs;
    refs.reserve(end - begin);
    for (uint32_t k = begin; k < end; ++k) {
      const uint32_t id = g.lists.refs[k];
      const LeafTriangle& t = g.tris[id];
      Aabb b;
      b.extend(t.p0);
      b.extend(t.p1);
      b.extend(t.p2);
      // Clip to the cell; the overlap test guarantees a non-empty result.
      Aabb clipped(b.lo.cwiseMax(cell_box.lo), b.hi.cwiseMin(cell_box.hi));
      if (clipped.is_empty()) clipped = b;
      refs.push_back(BuildRef::make(clipped, clipped.center(), id));
    }
    BuildOptions bo;
    bo.max_leaf = leaf;
    bo.leaf_threshold = 1;
    BinaryBvh tree = build_binned_sah(std::move(refs), bo);
    p.nodes.assign(tree.nodes.begin(), tree.nodes.end());  // a small tree per cell, joined into one array below
    p.tris.reserve(tree.prim_ids.size());
    for (const uint32_t id : tree.prim_ids) p.tris.push_back(g.tris[id]);
  });
  for (const auto& p : parts) add_to_totals(f.totals, measure_tree(p.nodes), p.tris.size());
  join_parts(g, cells, parts, f, [](const Bvh2Node* nodes, const LeafTriangle* tris, const uint32_t*, const auto& p) {
    return Bvh2View{nodes, tris, p.tris.empty()};
  });
  return f;
}

CellKdForest build_cell_kdtrees(const TopGrid& g, const KdBuildOptions& options) {
  CellKdForest f;
  if (g.empty) return f;
  const std::vector<uint32_t> cells = occupied_cells(g);
  auto parts = build_parts<KdNode>(cells, [&](uint32_t cell, CellPart<KdNode>& p) {
    const uint32_t begin = g.lists.offsets[cell], end = g.lists.offsets[cell + 1];
    // The cell's triangles as a small mesh of their own (local ids).
    TriangleMesh sub;
    for (uint32_t k = begin; k < end; ++k) {
      const LeafTriangle& t = g.tris[g.lists.refs[k]];
      const uint32_t v = static_cast<uint32_t>(sub.vertices.size());
      sub.vertices.insert(sub.vertices.end(), {t.p0, t.p1, t.p2});
      sub.triangles.push_back({v, v + 1, v + 2});
      p.tris.push_back(t);  // keeps the global id
    }
    KdTree tree = build_kdtree_sah(sub, options);
    p.nodes = std::move(tree.nodes);
    p.ids = std::move(tree.prim_ids);
    p.bounds = tree.bounds;
  });
  for (const auto& p : parts) {
    const KdTreeShape s = measure_kdtree(p.bounds, p.nodes);
    add_to_totals(f.totals, s, s.references);
  }
  join_parts(g, cells, parts, f, [](const KdNode* nodes, const LeafTriangle* tris, const uint32_t* ids, const auto& p) {
    return KdTreeView{nodes, tris, ids, p.bounds, p.tris.empty()};
  });
  return f;
}

}  // namespace raylab
