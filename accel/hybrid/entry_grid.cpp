#include "accel/hybrid/entry_grid.h"

#include <tbb/parallel_for.h>

#include "accel/kdtree/build_sah_events.h"

namespace raylab {

namespace {

// The deepest node whose cell contains [lo, hi] (double precision, closed
// boxes: a grid cell touching a split plane from one side belongs to that side).
EntryNode find_entry(const std::vector<KdNode>& nodes, const Aabb& bounds, const double lo[3], const double hi[3]) {
  EntryNode e;
  e.region = bounds;
  while (!nodes[e.node].is_leaf()) {
    const KdNode& n = nodes[e.node];
    const int k = n.axis();
    const double s = n.split();
    if (hi[k] <= s) {
      e.node = n.child();
      e.region.hi[k] = n.split();
    } else if (lo[k] >= s) {
      e.node = n.child() + 1;
      e.region.lo[k] = n.split();
    } else {
      break;
    }
    e.depth++;
  }
  return e;
}

}  // namespace

EntryGrid build_entry_grid(const TriangleMesh& mesh, double density, const KdBuildOptions& options) {
  EntryGrid g;
  g.top = build_top_grid(mesh, density, false);
  if (g.top.empty) return g;
  KdTree tree = build_kdtree_sah(mesh, options);
  g.nodes = std::move(tree.nodes);
  g.ids = std::move(tree.prim_ids);
  g.bounds = tree.bounds;
  g.root = KdTreeView{g.nodes.data(), g.top.tris.data(), g.ids.data(), g.bounds, false, 0};

  const DdaGrid& d = g.top.dda;
  g.entry.resize(d.cells());
  tbb::parallel_for(int32_t{0}, d.res[2], [&](int32_t z) {
    for (int32_t y = 0; y < d.res[1]; ++y)
      for (int32_t x = 0; x < d.res[0]; ++x) {
        const int32_t c[3] = {x, y, z};
        double lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
          lo[a] = d.boundary(a, c[a]);
          hi[a] = d.boundary(a, c[a] + 1);
        }
        g.entry[d.index(x, y, z)] = find_entry(g.nodes, g.bounds, lo, hi);
      }
  });
  return g;
}

}  // namespace raylab
