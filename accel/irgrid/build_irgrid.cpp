#include "accel/irgrid/build_irgrid.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <new>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "accel/core/grid/cell_overlap.h"
#include "accel/core/grid/grid_stats.h"
#include "accel/core/simd/leaf_blocks.h"

namespace raylab {

namespace {

// Cost model of the octree splits and the merge pass (the paper's SAH-like
// expected cost of a cell): a ray entering a cell pays one step (opt.step_cost,
// in triangle tests) plus one test per triangle, and enters it with a
// probability proportional to its surface area.

// Largest top grid the builder lays out (4M cells: 16 MiB of root entries),
// and the largest virtual grid side (voxel coordinates stay in int32 and
// exact in double).
constexpr uint64_t kMaxTopCells = uint64_t{1} << 22;
constexpr int32_t kMaxVirtualAxisVoxels = int32_t{1} << 30;

// A cell while building: its own (merged) box, the box expansion grew, and
// its sorted triangle ids.
struct BuildCell {
  int32_t lo[3], hi[3];
  int32_t exp_lo[3], exp_hi[3];
  std::vector<uint32_t> tris;
  int level = 0;  // octree level (0: a whole top cell)
  bool alive = true;
};

class IrgridBuilder {
 public:
  IrgridBuilder(Irgrid& g, const IrgridOptions& opt) : g_(g), opt_(opt) {}

  void build(const TriangleMesh& mesh, BuildStats& stats);

 private:
  struct LocalTree {
    std::vector<BuildCell> cells;
    std::vector<uint32_t> nodes;
    uint32_t root = 0;
  };
  void subdivide_top_cells(const std::vector<uint32_t>& top_offsets, const std::vector<uint32_t>& top_refs);
  uint32_t subdivide(LocalTree& tree, const int32_t lo[3], int level, std::vector<uint32_t>& tris) const;
  size_t merge_cells();
  size_t expand_cells();
  void finish(BuildStats& stats);
  void make_leaf_blocks(const TriangleMesh& mesh);

  // Calls f(entry) for every leaf entry of the voxel map (a cell id, by
  // reference) whose octree node overlaps the virtual box [lo, hi).
  template <typename F>
  void for_each_leaf(const int32_t lo[3], const int32_t hi[3], F&& f);
  template <typename F>
  void descend(uint32_t& entry, const int32_t node_lo[3], int level, const int32_t lo[3], const int32_t hi[3], F& f);
  double cost(const int32_t lo[3], const int32_t hi[3], size_t triangles) const;

  Irgrid& g_;
  const IrgridOptions& opt_;
  // The cell owning virtual voxel v, in the binary octrees.
  uint32_t tree_cell_at(const int32_t v[3]) const;
  // The walk's voxel map (irgrid.h) from the binary octrees.
  void flatten_voxel_map();
  int subtree_height(uint32_t entry);
  uint32_t flatten(uint32_t entry);

  std::vector<BuildCell> cells_;
  // The voxel map while building: per top cell a binary octree, entries as
  // in irgrid.h with one level per block (blocks of 8).
  std::vector<uint32_t> tree_top_, tree_nodes_;
  std::vector<int8_t> block_height_;  // per block of tree_nodes_, -1 = not computed
  int deepest_ = 0;
};

uint32_t IrgridBuilder::tree_cell_at(const int32_t v[3]) const {
  uint32_t e = tree_top_[g_.top.index(v[0] >> g_.depth, v[1] >> g_.depth, v[2] >> g_.depth)];
  for (int bit = g_.depth - 1; e & kIrgridInnerNode; --bit) {
    const uint32_t child = ((v[0] >> bit) & 1) | (((v[1] >> bit) & 1) << 1) | (((v[2] >> bit) & 1) << 2);
    e = tree_nodes_[(e & ~kIrgridInnerNode) + child];
  }
  return e;
}

int IrgridBuilder::subtree_height(uint32_t entry) {
  if (!(entry & kIrgridInnerNode)) return 0;
  const uint32_t block = entry & ~kIrgridInnerNode;
  int8_t& h = block_height_[block / 8];
  if (h < 0) {
    int most = 0;
    for (uint32_t c = 0; c < 8; ++c) most = std::max(most, subtree_height(tree_nodes_[block + c]));
    h = static_cast<int8_t>(1 + most);
  }
  return h;
}

// An inner node of the binary octree becomes one block of (2^k)^3 entries
// covering k levels at once, k = min(3, the height of its subtree): the
// walk's lookup then makes a third of the dependent loads of a binary
// descent, and a shallow subtree costs no more entries than before.
uint32_t IrgridBuilder::flatten(uint32_t entry) {
  if (!(entry & kIrgridInnerNode)) return entry;
  const int k = std::min(kIrgridMaxLevelsPerBlock, subtree_height(entry));
  const uint32_t side = 1u << k;
  const size_t base = g_.nodes.size();
  if (base + (size_t{1} << (3 * k)) > kIrgridBlockMask)
    throw std::length_error("irgrid: voxel map larger than 2^29 entries");
  g_.nodes.resize(base + (size_t{1} << (3 * k)));
  for (uint32_t z = 0; z < side; ++z)
    for (uint32_t y = 0; y < side; ++y)
      for (uint32_t x = 0; x < side; ++x) {
        uint32_t e = entry;
        int level = k - 1;
        for (; level >= 0 && (e & kIrgridInnerNode); --level) {
          const uint32_t child = ((x >> level) & 1) | (((y >> level) & 1) << 1) | (((z >> level) & 1) << 2);
          e = tree_nodes_[(e & ~kIrgridInnerNode) + child];
        }
        const uint32_t flat = (e & kIrgridInnerNode) ? flatten(e) : e;
        g_.nodes[base + x + (y << k) + (z << (2 * k))] = flat;
      }
  return kIrgridInnerNode | (static_cast<uint32_t>(k) << kIrgridLevelsShift) | static_cast<uint32_t>(base);
}

void IrgridBuilder::flatten_voxel_map() {
  block_height_.assign(tree_nodes_.size() / 8 + 1, -1);
  g_.top_nodes.resize(tree_top_.size());
  for (size_t t = 0; t < tree_top_.size(); ++t) g_.top_nodes[t] = flatten(tree_top_[t]);
  std::vector<uint32_t>().swap(tree_nodes_);
  std::vector<uint32_t>().swap(tree_top_);
}

template <typename F>
void IrgridBuilder::descend(uint32_t& entry, const int32_t node_lo[3], int level, const int32_t lo[3],
                            const int32_t hi[3], F& f) {
  if (!(entry & kIrgridInnerNode)) {
    f(entry);
    return;
  }
  const int32_t half = int32_t{1} << (g_.depth - level - 1);
  const uint32_t block = entry & ~kIrgridInnerNode;
  for (uint32_t c = 0; c < 8; ++c) {
    int32_t child_lo[3];
    bool overlaps = true;
    for (int k = 0; k < 3; ++k) {
      child_lo[k] = node_lo[k] + (((c >> k) & 1) ? half : 0);
      overlaps &= child_lo[k] < hi[k] && child_lo[k] + half > lo[k];
    }
    if (overlaps) descend(tree_nodes_[block + c], child_lo, level + 1, lo, hi, f);
  }
}

template <typename F>
void IrgridBuilder::for_each_leaf(const int32_t lo[3], const int32_t hi[3], F&& f) {
  const int D = g_.depth;
  int32_t t[3];
  for (t[2] = lo[2] >> D; t[2] <= (hi[2] - 1) >> D; ++t[2])
    for (t[1] = lo[1] >> D; t[1] <= (hi[1] - 1) >> D; ++t[1])
      for (t[0] = lo[0] >> D; t[0] <= (hi[0] - 1) >> D; ++t[0]) {
        const int32_t node_lo[3] = {t[0] << D, t[1] << D, t[2] << D};
        descend(tree_top_[g_.top.index(t[0], t[1], t[2])], node_lo, 0, lo, hi, f);
      }
}

double IrgridBuilder::cost(const int32_t lo[3], const int32_t hi[3], size_t triangles) const {
  const double dx = (hi[0] - lo[0]) * g_.virt.cell[0], dy = (hi[1] - lo[1]) * g_.virt.cell[1],
               dz = (hi[2] - lo[2]) * g_.virt.cell[2];
  const double area = dx * dy + dy * dz + dz * dx;
  return area * (opt_.step_cost + static_cast<double>(triangles));
}

// Step 1 (paper section 4.1): each top cell is split by an octree. A node
// with n triangles is split in 8 when the second-level density rule of the
// two-level grid (Kalojanov et al. 2011) asks for more than one cell there,
// lambda_2 n > 8, and the children's expected cost is lower than the node's
// as a leaf, with the probability of entering a child given the node = the
// ratio of their surface areas (1/4 each, 2 children per ray on average):
//   2 step + (1/4) sum_children n_c  <  step + n,
// and unless one child keeps all n while the triangles spread over the whole
// node: a vertex shared by many triangles lies in one child at every scale
// and would split down to the depth limit (a small object inside one child
// still splits: its box fits in the child).
// Applied node by node, the density rule adapts the depth to where the
// triangles are (a dense object in a big top cell gets a deep subtree).
// Triangles go to the children they overlap exactly (separating axes,
// accel/grid/tri_box_overlap.h) with the grids' cell margin.
uint32_t IrgridBuilder::subdivide(LocalTree& tree, const int32_t lo[3], int level, std::vector<uint32_t>& tris) const {
  const int32_t side = int32_t{1} << (g_.depth - level);
  if (level < g_.depth && opt_.sub_density * static_cast<double>(tris.size()) > 8.0) {
    const int32_t half = side >> 1;
    std::vector<uint32_t> kids[8];
    Vec3d box_lo[8], box_hi[8];
    for (int c = 0; c < 8; ++c)
      for (int k = 0; k < 3; ++k) {
        const int32_t clo = lo[k] + (((c >> k) & 1) ? half : 0);
        const double margin = kCellMarginRelative * half * g_.virt.cell[k] + kCellMarginUlps * g_.virt.error_scale;
        box_lo[c][k] = g_.virt.boundary(k, clo) - margin;
        box_hi[c][k] = g_.virt.boundary(k, clo + half) + margin;
      }
    size_t child_refs = 0, largest = 0;
    for (const uint32_t id : tris) {
      const LeafTriangle& t = g_.tris[id];
      const Vec3d v0 = t.p0.cast<double>(), v1 = t.p1.cast<double>(), v2 = t.p2.cast<double>();
      for (int c = 0; c < 8; ++c)
        if (triangle_box_overlap(box_lo[c], box_hi[c], v0, v1, v2)) {
          kids[c].push_back(id);
          ++child_refs;
        }
    }
    for (const auto& k : kids) largest = std::max(largest, k.size());
    bool separates = largest < tris.size();
    if (!separates) {
      // Do the triangles' boxes, clipped to the node, fit in half of it on every axis?
      Vec3d node_lo, node_hi;
      for (int k = 0; k < 3; ++k) {
        node_lo[k] = g_.virt.boundary(k, lo[k]);
        node_hi[k] = g_.virt.boundary(k, lo[k] + side);
      }
      Vec3d used_lo = node_hi, used_hi = node_lo;
      for (const uint32_t id : tris) {
        const LeafTriangle& t = g_.tris[id];
        const Vec3d tlo = t.p0.cwiseMin(t.p1).cwiseMin(t.p2).cast<double>().cwiseMax(node_lo);
        const Vec3d thi = t.p0.cwiseMax(t.p1).cwiseMax(t.p2).cast<double>().cwiseMin(node_hi);
        used_lo = used_lo.cwiseMin(tlo);
        used_hi = used_hi.cwiseMax(thi);
      }
      separates = ((used_hi - used_lo).array() <= 0.5 * (node_hi - node_lo).array()).all();
    }
    if (separates &&
        opt_.step_cost + 0.25 * static_cast<double>(child_refs) < static_cast<double>(tris.size())) {
      std::vector<uint32_t>().swap(tris);
      const uint32_t block = static_cast<uint32_t>(tree.nodes.size());
      tree.nodes.resize(block + 8);
      for (int c = 0; c < 8; ++c) {
        const int32_t clo[3] = {lo[0] + ((c & 1) ? half : 0), lo[1] + ((c & 2) ? half : 0),
                                lo[2] + ((c & 4) ? half : 0)};
        const uint32_t e = subdivide(tree, clo, level + 1, kids[c]);
        tree.nodes[block + c] = e;
      }
      return block | kIrgridInnerNode;
    }
  }
  const uint32_t id = static_cast<uint32_t>(tree.cells.size());
  BuildCell& cell = tree.cells.emplace_back();
  for (int k = 0; k < 3; ++k) {
    cell.lo[k] = cell.exp_lo[k] = lo[k];
    cell.hi[k] = cell.exp_hi[k] = lo[k] + side;
  }
  cell.tris.swap(tris);
  cell.level = level;
  return id;
}

// Every top cell's octree, built in parallel, then numbered into the global
// arrays (cells in top-cell order, depth first inside each).
void IrgridBuilder::subdivide_top_cells(const std::vector<uint32_t>& top_offsets,
                                        const std::vector<uint32_t>& top_refs) {
  const size_t top_cells = g_.top.cells();
  std::vector<LocalTree> trees(top_cells);
  tbb::parallel_for(size_t{0}, top_cells, [&](size_t t) {
    const int32_t lo[3] = {static_cast<int32_t>(t % g_.top.res[0]) << g_.depth,
                           static_cast<int32_t>((t / g_.top.res[0]) % g_.top.res[1]) << g_.depth,
                           static_cast<int32_t>(t / (static_cast<size_t>(g_.top.res[0]) * g_.top.res[1])) << g_.depth};
    // top_refs are in increasing id order, so every leaf's list is sorted.
    std::vector<uint32_t> tris(top_refs.begin() + top_offsets[t], top_refs.begin() + top_offsets[t + 1]);
    trees[t].root = subdivide(trees[t], lo, 0, tris);
  });
  size_t cells = 0, nodes = 0;
  for (const LocalTree& tree : trees) {
    cells += tree.cells.size();
    nodes += tree.nodes.size();
  }
  if (cells >= kIrgridInnerNode || nodes >= kIrgridInnerNode)
    throw std::length_error("irgrid: more than 2^31 cells or octree entries");
  cells_.reserve(cells);
  tree_nodes_.reserve(nodes);
  tree_top_.resize(top_cells);
  for (size_t t = 0; t < top_cells; ++t) {
    LocalTree& tree = trees[t];
    const uint32_t cell_base = static_cast<uint32_t>(cells_.size()), node_base = static_cast<uint32_t>(tree_nodes_.size());
    auto global = [&](uint32_t e) { return (e & kIrgridInnerNode) ? e + node_base : e + cell_base; };
    tree_top_[t] = global(tree.root);
    for (const uint32_t e : tree.nodes) tree_nodes_.push_back(global(e));
    for (BuildCell& c : tree.cells) {
      deepest_ = std::max(deepest_, c.level);
      cells_.push_back(std::move(c));
    }
    LocalTree().cells.swap(tree.cells);
  }
}

// Step 2 (paper section 4.2): neighbours along an axis whose shared faces
// coincide are merged when the merged cell's expected cost is not larger
// than the two cells' together. Each round pairs every cell with at most
// one neighbour (so runs of cells merge as balanced pairs, as the paper's
// parallel merge does), alternating the axes until no pair merges.
//
// A round is the sequential scan "for each cell i in order: merge i with its
// neighbour j if neither is taken yet and the cost allows" in two phases.
// The costly part, each cell's candidate and its cost test (a list union),
// runs in parallel on the cells as they were at the start of the round;
// then the scan takes the pairs in order. The result is the sequential
// scan's: a pair the scan merges involves two cells no earlier pair of the
// round touched, so they still are as at the start of the round, and a
// voxel map entry an earlier merge rewrote belongs to a taken cell either
// way. Hence the same cells for any thread count.
size_t IrgridBuilder::merge_cells() {
  constexpr uint32_t kNone = UINT32_MAX;
  size_t merges = 0;
  std::vector<uint8_t> touched(cells_.size());
  std::vector<uint32_t> partner(cells_.size());
  for (bool any = true; any;) {
    any = false;
    for (int a = 0; a < 3; ++a) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      tbb::parallel_for(tbb::blocked_range<uint32_t>(0, static_cast<uint32_t>(cells_.size()), 1024),
                        [&](const tbb::blocked_range<uint32_t>& range) {
        std::vector<uint32_t> merged_tris;
        for (uint32_t i = range.begin(); i != range.end(); ++i) {
          partner[i] = kNone;
          const BuildCell& A = cells_[i];
          if (!A.alive || A.hi[a] >= g_.virt.res[a]) continue;
          int32_t v[3] = {A.lo[0], A.lo[1], A.lo[2]};
          v[a] = A.hi[a];
          const uint32_t j = tree_cell_at(v);
          const BuildCell& B = cells_[j];
          if (B.lo[a] != A.hi[a] || B.lo[b] != A.lo[b] || B.hi[b] != A.hi[b] || B.lo[c] != A.lo[c] ||
              B.hi[c] != A.hi[c])
            continue;
          merged_tris.clear();
          std::set_union(A.tris.begin(), A.tris.end(), B.tris.begin(), B.tris.end(), std::back_inserter(merged_tris));
          int32_t mhi[3] = {A.hi[0], A.hi[1], A.hi[2]};
          mhi[a] = B.hi[a];
          if (cost(A.lo, mhi, merged_tris.size()) > cost(A.lo, A.hi, A.tris.size()) + cost(B.lo, B.hi, B.tris.size()))
            continue;
          partner[i] = j;
        }
      });
      std::fill(touched.begin(), touched.end(), 0);
      std::vector<uint32_t> merged_tris;
      for (uint32_t i = 0; i < cells_.size(); ++i) {
        const uint32_t j = partner[i];
        if (j == kNone || touched[i] || touched[j]) continue;
        BuildCell& A = cells_[i];
        BuildCell& B = cells_[j];
        merged_tris.clear();
        std::set_union(A.tris.begin(), A.tris.end(), B.tris.begin(), B.tris.end(), std::back_inserter(merged_tris));
        for_each_leaf(B.lo, B.hi, [&](uint32_t& entry) { entry = i; });
        A.hi[a] = A.exp_hi[a] = B.hi[a];
        A.tris.swap(merged_tris);
        B.alive = false;
        std::vector<uint32_t>().swap(B.tris);
        touched[i] = touched[j] = 1;
        any = true;
        ++merges;
      }
    }
  }
  return merges;
}

// Step 3 (paper section 4.3): each cell's box grows over a neighbouring slab
// when every cell owning part of it is empty or holds only triangles this
// cell already lists, so a ray leaves the cell farther along at no extra
// test. The slab goes as far as the nearest far face of the cells it
// crosses (they own the whole slab up to there). Only the cell's own box
// grows: the voxel map still names each voxel's owner. At most
// kExpandRounds rounds over the six faces: a cell next to a deep octree
// region would otherwise creep over its tiny cells one at a time.
constexpr int kExpandRounds = 3;

// Each cell grows its own expanded box (exp_lo, exp_hi) and reads only the
// other cells' merged boxes and lists, which this pass leaves unchanged: the
// cells expand in parallel, with the same result for any thread count.
size_t IrgridBuilder::expand_cells() {
  std::vector<uint8_t> grew(cells_.size(), 0);
  tbb::parallel_for(uint32_t{0}, static_cast<uint32_t>(cells_.size()), [&](uint32_t i) {
    BuildCell& C = cells_[i];
    if (!C.alive) return;
    bool cell_grew = false;
    for (int round = 0, any = 1; any && round < kExpandRounds; ++round) {
      any = 0;
      for (int face = 0; face < 6; ++face) {
        const int a = face >> 1;
        const bool up = face & 1;
        if (up ? C.exp_hi[a] >= g_.virt.res[a] : C.exp_lo[a] <= 0) continue;
        int32_t lo[3] = {C.exp_lo[0], C.exp_lo[1], C.exp_lo[2]}, hi[3] = {C.exp_hi[0], C.exp_hi[1], C.exp_hi[2]};
        if (up) {
          lo[a] = C.exp_hi[a];
          hi[a] = lo[a] + 1;
        } else {
          hi[a] = C.exp_lo[a];
          lo[a] = hi[a] - 1;
        }
        bool ok = true;
        int32_t reach = up ? g_.virt.res[a] : 0;
        uint32_t last = UINT32_MAX;
        for_each_leaf(lo, hi, [&](uint32_t& entry) {
          const uint32_t j = entry;
          if (!ok || j == last) return;
          last = j;
          const BuildCell& N = cells_[j];
          ok = N.tris.empty() || std::includes(C.tris.begin(), C.tris.end(), N.tris.begin(), N.tris.end());
          reach = up ? std::min(reach, N.hi[a]) : std::max(reach, N.lo[a]);
        });
        if (!ok) continue;
        (up ? C.exp_hi[a] : C.exp_lo[a]) = reach;
        any = 1;
        cell_grew = true;
      }
    }
    grew[i] = cell_grew;
  });
  size_t grown = 0;
  for (const uint8_t g : grew) grown += g;
  return grown;
}

// The alive cells, renumbered, with their lists in one array.
void IrgridBuilder::finish(BuildStats& stats) {
  std::vector<uint32_t> new_id(cells_.size(), UINT32_MAX);
  uint64_t refs = 0, nonempty = 0;
  uint32_t max_per_cell = 0;
  for (uint32_t i = 0; i < cells_.size(); ++i) {
    if (!cells_[i].alive) continue;
    new_id[i] = static_cast<uint32_t>(g_.cells.size());
    const BuildCell& b = cells_[i];
    IrgridCell c;
    for (int k = 0; k < 3; ++k) {
      c.lo[k] = b.exp_lo[k];
      c.hi[k] = b.exp_hi[k];
    }
    c.begin = static_cast<uint32_t>(refs);
    c.count = static_cast<uint32_t>(b.tris.size());
    refs += c.count;
    nonempty += c.count != 0;
    max_per_cell = std::max(max_per_cell, c.count);
    g_.cells.push_back(c);
  }
  if (refs >= (uint64_t{1} << 32)) throw std::length_error("irgrid: more than 2^32 triangle references");
  g_.refs.reserve(refs);
  for (const BuildCell& b : cells_)
    if (b.alive) g_.refs.insert(g_.refs.end(), b.tris.begin(), b.tris.end());
  auto renumber = [&](uint32_t& e) {
    if (!(e & kIrgridInnerNode)) e = new_id[e];
  };
  for (uint32_t& e : tree_top_) renumber(e);
  for (uint32_t& e : tree_nodes_) renumber(e);
  flatten_voxel_map();
  add_occupancy_stats(stats, g_.cells.size(), nonempty, refs, max_per_cell, g_.tris.size());
}

// Leaf blocks (irgrid.h): each cell's record followed by its list as
// irgrid_blocks(count) blocks, cells in order, and the voxel map's
// leaf entries rewritten from cell ids to record positions. The slabs
// replace the cells, the ids and the triangle copies.
void IrgridBuilder::make_leaf_blocks(const TriangleMesh& mesh) {
  std::vector<uint64_t> at(g_.cells.size() + 1, 0);
  for (size_t i = 0; i < g_.cells.size(); ++i) at[i + 1] = at[i] + Irgrid::slab_chunks(g_.cells[i].count);
  if (at.back() >= kIrgridInnerNode) throw std::length_error("irgrid: more than 2^31 chunks of leaf blocks");
  g_.slabs.resize(at.back());
  tbb::parallel_for(size_t{0}, g_.cells.size(), [&](size_t i) {
    IrgridCell c = g_.cells[i];
    const uint32_t* ids = g_.refs.data() + c.begin;
    IrgridChunk* slab = g_.slabs.data() + at[i];
    c.begin = static_cast<uint32_t>(at[i] + 1);
    new (slab) IrgridCell(c);
    // The blocks follow the record, kIrgridChunksPerBlock chunks each.
    auto* blocks = reinterpret_cast<IrgridTriangleBlock*>(slab + 1);
    std::uninitialized_default_construct_n(blocks, irgrid_blocks(c.count));
    fill_leaf_blocks<kIrgridBlockWidth>(mesh, ids, c.count, std::launder(blocks));
  });
  auto to_slab = [&](uint32_t& e) {
    if (!(e & kIrgridInnerNode)) e = static_cast<uint32_t>(at[e]);
  };
  for (uint32_t& e : g_.top_nodes) to_slab(e);
  for (uint32_t& e : g_.nodes) to_slab(e);
  std::vector<IrgridCell>().swap(g_.cells);
  std::vector<uint32_t>().swap(g_.refs);
  std::vector<LeafTriangle>().swap(g_.tris);
  g_.leaf_blocks = true;
}

void IrgridBuilder::build(const TriangleMesh& mesh, BuildStats& stats) {
  const size_t n = g_.tris.size();
  Vec3d lo, hi;
  padded_grid_box(mesh.bounds(), lo, hi);
  const Aabb bounds = mesh.bounds();
  const Vec3d extent = (bounds.hi - bounds.lo).cast<double>();

  // The top grid, by the density rule (grid_resolution.h), small enough that
  // its refinement by 2^max_depth stays within kMaxVirtualAxisVoxels per axis.
  const uint64_t axis_cap = static_cast<uint64_t>(kMaxVirtualAxisVoxels >> opt_.max_depth);
  const double cap_cells = std::min(static_cast<double>(kMaxTopCells), std::pow(static_cast<double>(axis_cap), 3.0));
  ChosenResolution chosen =
      choose_resolution(extent, static_cast<double>(n), opt_.top_density, static_cast<uint64_t>(cap_cells));
  GridRes& res = chosen.res;
  for (int a = 0; a < 3; ++a) res[a] = std::min<int32_t>(res[a], static_cast<int32_t>(axis_cap));
  g_.top = make_dda_grid(lo, hi, res);

  // Top-level references, exact overlap with the cells' margins.
  std::vector<uint64_t> pairs;  // cell << 32 | triangle
  for (uint32_t t = 0; t < n; ++t) {
    const LeafTriangle& tri = g_.tris[t];
    for_each_assigned_cell(g_.top, AssignMode::Exact, tri.p0, tri.p1, tri.p2, [&](int32_t x, int32_t y, int32_t z) {
      pairs.push_back(static_cast<uint64_t>(g_.top.index(x, y, z)) << 32 | t);
    });
  }
  tbb::parallel_sort(pairs.begin(), pairs.end());
  const size_t top_cells = g_.top.cells();
  std::vector<uint32_t> top_offsets(top_cells + 1, 0), top_refs(pairs.size());
  for (size_t r = 0; r < pairs.size(); ++r) {
    top_offsets[(pairs[r] >> 32) + 1]++;
    top_refs[r] = static_cast<uint32_t>(pairs[r]);
  }
  std::vector<uint64_t>().swap(pairs);
  for (size_t t = 0; t < top_cells; ++t) top_offsets[t + 1] += top_offsets[t];

  // The virtual grid: the top grid refined to the deepest level allowed.
  g_.depth = opt_.max_depth;
  double vcell[3];
  int32_t vres[3];
  for (int a = 0; a < 3; ++a) {
    vcell[a] = std::ldexp(g_.top.cell[a], -g_.depth);  // exact: top boundaries are virtual boundaries
    vres[a] = g_.top.res[a] << g_.depth;
  }
  g_.virt = make_dda_grid_from_cells(g_.top.lo, vcell, vres);
  g_.virt.error_scale = g_.top.error_scale;

  subdivide_top_cells(top_offsets, top_refs);
  const size_t initial = cells_.size();
  stats.extra["initial_cells"] = static_cast<double>(initial);
  stats.extra["merged_pairs"] = opt_.merge ? static_cast<double>(merge_cells()) : 0.0;
  stats.extra["expanded_cells"] = opt_.expand ? static_cast<double>(expand_cells()) : 0.0;
  finish(stats);
  if (opt_.leaf_blocks) make_leaf_blocks(mesh);
  stats.extra["top_x"] = g_.top.res[0];
  stats.extra["top_y"] = g_.top.res[1];
  stats.extra["top_z"] = g_.top.res[2];
  stats.extra["depth"] = deepest_;
  stats.max_depth = deepest_;
}

}  // namespace

Irgrid build_irgrid(const TriangleMesh& mesh, const IrgridOptions& opt, BuildStats& stats) {
  Irgrid g;
  const size_t n = mesh.num_triangles();
  if (n >= (size_t{1} << 32) - 1) throw std::length_error("irgrid: more than 2^32 - 2 triangles");
  g.tris = copy_leaf_triangles(mesh);
  g.empty = n == 0;
  if (g.empty) return g;
  IrgridBuilder(g, opt).build(mesh, stats);
  stats.bytes = g.bytes();
  return g;
}

}  // namespace raylab
