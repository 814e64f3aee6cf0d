// The binary BVH builders (binned and sweep SAH, SBVH, pre-splitting, LBVH,
// the small-range sweep): well-formed trees holding every triangle inside
// enclosing boxes, their split choices against exhaustive references, and
// the spatial splits' and pre-split pieces' coverage of their triangles.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <map>
#include <vector>

#include <fmt/format.h>
#include <tbb/global_control.h>

#include "accel/bvh/build_binned_sah.h"
#include "accel/bvh/build_lbvh.h"
#include "accel/bvh/build_sbvh.h"
#include "accel/bvh/sah_binning.h"
#include "accel/bvh/small_sweep.h"
#include "accel/registry.h"
#include "base/pcg.h"
#include "tests/accel/bvh/bvh_test_util.h"
#include "tests/accel_test_util.h"

namespace raylab {
namespace {

using test::Prims;
using test::prims_of;
using test::build_with;
using test::is_leaf;
using test::check_binary_tree;

TEST(BvhBuilders, BinaryTreesHoldEveryTriangleOnceInsideEnclosingBoxes) {
  const test::NamedMesh s = test::soup(3000, 23);
  for (const char* b : {"binned", "sweep", "lbvh", "reinsert"}) {
    SCOPED_TRACE(b);
    check_binary_tree(build_with(b, s.mesh), s.mesh, false);
    check_binary_tree(build_with(b, s.mesh, 4), s.mesh, false);
  }
  check_binary_tree(build_with("sbvh", s.mesh), s.mesh, true);
}

// Small ranges are split by an exact sweep whose per-axis order is a rank
// sort: with centroids on a coarse lattice (many equal coordinates, and
// -0 beside +0) every rank must still be a distinct slot. A lost or doubled
// reference would show as a triangle seen zero or two times.
TEST(BvhBuilders, SmallRangesWithTiedCentroidsKeepEveryTriangle) {
  TriangleMesh m;
  Pcg32 rng(9, 3);
  const float lattice[] = {-1.0f, -0.0f, 0.0f, 1.0f};
  for (int i = 0; i < 1500; ++i) {
    const Vec3f c(lattice[rng.next() % 4], lattice[rng.next() % 4], lattice[rng.next() % 4]);
    const float h = (rng.next() % 2) ? 0.25f : 0.125f;  // two sizes: ties in centroids, not in boxes
    const auto v = static_cast<uint32_t>(m.vertices.size());
    m.vertices.push_back(Vec3f(c.x() - h, c.y() - h, c.z()));  // z kept exactly: a -0 plane stays -0
    m.vertices.push_back(Vec3f(c.x() + h, c.y() - h, c.z()));
    m.vertices.push_back(Vec3f(c.x(), c.y() + h, c.z()));
    m.triangles.push_back({v, v + 1, v + 2});
  }
  for (int threshold : {1, 2, 3, 4}) {
    SCOPED_TRACE(threshold);
    check_binary_tree(build_with("binned", m, threshold), m, false);
  }
}

// The small-node sweep's fast path (AVX-512 registers where built for it)
// must choose exactly what the portable sweep chooses: the same orders, axis,
// position and cost bits, so that the tree does not depend on the ISA. And
// the portable sweep must choose the cheapest split by a plain recount. Sets
// of 2..16 references: random boxes, centroids tied on a lattice (-0 beside
// +0), flat and point boxes, identical references, and coordinates near the
// float limit whose extents overflow (infinite and NaN costs).
TEST(BvhBuilders, SmallSweepChoosesTheCheapestSplitOnEveryPath) {
  Pcg32 rng(41, 7);
  const float lattice[] = {-1.0f, -0.0f, 0.0f, 1.0f};
  for (int trial = 0; trial < 4000; ++trial) {
    const int n = 2 + trial % 15;
    const int kind = (trial / 15) % 5;
    std::vector<BuildRef> refs;
    for (int i = 0; i < n; ++i) {
      Vec3f lo, hi;
      for (int a = 0; a < 3; ++a) {
        float l = 0.0f, h = 0.0f;
        switch (kind) {
          case 0: l = rng.uniform() * 10.0f - 5.0f; h = l + rng.uniform() * 3.0f; break;
          case 1: l = lattice[rng.next() % 4]; h = l + ((rng.next() % 2) ? 0.5f : 0.0f); break;
          case 2: l = h = lattice[rng.next() % 4]; break;                        // points and flat boxes
          case 3: l = -1.0f; h = 2.0f; break;                                    // identical references
          default: l = (rng.next() % 2 ? 1.0f : -1.0f) * 3.0e38f * rng.uniform();  // overflowing extents
                   h = (rng.next() % 3) ? l : std::max(l, 3.0e38f * rng.uniform());
        }
        lo[a] = l;
        hi[a] = h;
      }
      const Aabb box(lo, hi);
      refs.push_back(BuildRef::make(box, box.center(), static_cast<uint32_t>(i)));
    }
    SCOPED_TRACE(fmt::format("trial {} n {} kind {}", trial, n, kind));
    uint8_t fast_order[3][sah::kSmallSweepMax], order[3][sah::kSmallSweepMax];
    const sah::SmallSplit fast = sah::choose_small_split(refs.data(), n, fast_order);
    const sah::SmallSplit ref = sah::choose_small_split_scalar(refs.data(), n, order);
    ASSERT_EQ(fast.axis, ref.axis);
    ASSERT_EQ(fast.pos, ref.pos);
    ASSERT_EQ(std::bit_cast<uint32_t>(fast.cost), std::bit_cast<uint32_t>(ref.cost));
    for (int a = 0; a < 3; ++a) ASSERT_TRUE(std::equal(order[a], order[a] + n, fast_order[a])) << "axis " << a;
    ASSERT_GE(ref.axis, 0);
    ASSERT_LE(ref.axis, 2);
    ASSERT_GE(ref.pos, 1);
    ASSERT_LT(ref.pos, n);
    // The orders: permutations, sorted by centroid (ties by index).
    for (int a = 0; a < 3; ++a) {
      std::vector<int> seen(n, 0);
      for (int i = 0; i < n; ++i) seen[order[a][i]]++;
      ASSERT_EQ(std::count(seen.begin(), seen.end(), 1), n);
      for (int i = 1; i < n; ++i) {
        const float p = refs[order[a][i - 1]].box.aabb().center()[a], q = refs[order[a][i]].box.aabb().center()[a];
        ASSERT_TRUE(p < q || (p == q && order[a][i - 1] < order[a][i]) || std::signbit(p) != std::signbit(q))
            << "axis " << a << " position " << i;
      }
    }
    // The cost recounted, and no split of any axis cheaper.
    const auto split_cost = [&](int a, int pos) {
      Box4 l, r;
      for (int i = 0; i < n; ++i) (i < pos ? l : r).extend(refs[order[a][i]].box);
      const float c = l.half_area() * static_cast<float>(pos) + r.half_area() * static_cast<float>(n - pos);
      return c == c ? c : std::numeric_limits<float>::infinity();
    };
    ASSERT_EQ(std::bit_cast<uint32_t>(split_cost(ref.axis, ref.pos)), std::bit_cast<uint32_t>(ref.cost));
    for (int a = 0; a < 3; ++a)
      for (int pos = 1; pos < n; ++pos) ASSERT_GE(split_cost(a, pos), ref.cost) << "axis " << a << " pos " << pos;
  }
}

// The partitions test a reference against a bin boundary with one scalar
// lane (Binning::left_of) and must agree with the bins the SAH counted
// (Binning::bins_of), or a child's box (taken from its bins) would miss a
// reference: centroids inside, on and outside the binned bounds, NaN, and
// the largest floats.
TEST(BvhBuilders, BoundaryTestAgreesWithTheBins) {
  Pcg32 rng(5, 11);
  Box4 cb;
  cb.extend(_mm_setr_ps(-2.0f, 0.0f, 1.0e-3f, 0.0f));
  cb.extend(_mm_setr_ps(6.0f, 1.0e-30f, 3.0e38f, 0.0f));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int bins : {2, 8, 16, 64, 256}) {
    const sah::Binning bn(cb, bins);
    for (int t = 0; t < 20000; ++t) {
      float c[3];
      for (int a = 0; a < 3; ++a) {
        const float lo = cb.lo_at(a), hi = cb.hi_at(a);
        switch (rng.next() % 6) {
          case 0: c[a] = lo; break;
          case 1: c[a] = hi; break;
          case 2: c[a] = lo - (hi - lo) * rng.uniform(); break;
          case 3: c[a] = (rng.next() % 2 ? 1.0f : -1.0f) * std::numeric_limits<float>::max(); break;
          case 4: c[a] = (t % 97 == 0) ? nan : lo + (hi - lo) * rng.uniform(); break;
          default: c[a] = lo + (hi - lo) * (std::floor(rng.uniform() * bins) / bins);  // on a bin boundary
        }
      }
      const BuildRef r = BuildRef::make(Aabb(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), Vec3f(c[0], c[1], c[2]), 0);
      alignas(16) int32_t bin[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(bin), bn.bins_of(r));
      for (int a = 0; a < 3; ++a)
        for (int pos = 1; pos < bins; ++pos)
          ASSERT_EQ(bn.left_of(r, a, pos), bin[a] < pos)
              << "bins " << bins << " axis " << a << " centroid " << c[a] << " pos " << pos;
    }
  }
}

// bin_refs spreads long ranges over two or four bin sets (and the longest
// over threads) and merges them: the same boxes and counts as binning the
// references one by one into one set, for every range length's path and
// remainder.
TEST(BvhBuilders, BinningMatchesOneByOne) {
  const test::NamedMesh s = test::soup(40000, 17, 0.05f);
  const Prims p = prims_of(s.mesh);
  const std::vector<BuildRef> refs = make_build_refs(p.boxes, p.centroids);
  for (size_t n : {size_t{7}, size_t{255}, size_t{256}, size_t{1001}, size_t{2047}, size_t{2048}, size_t{5003},
                   size_t{40000}}) {
    for (int nb : {8, 64}) {
      SCOPED_TRACE(fmt::format("{} references, {} bins", n, nb));
      const size_t b = refs.size() - n;
      Box4 cb;
      for (size_t i = b; i < refs.size(); ++i) cb.extend(refs[i].centroid());
      const sah::Binning bn(cb, nb);
      const auto bins = sah::bin_refs(refs.data(), b, refs.size(), bn, nb);
      std::vector<Box4> box(3 * nb);
      std::vector<uint32_t> count(3 * nb, 0);
      for (size_t i = b; i < refs.size(); ++i) {
        alignas(16) int32_t bin[4];
        _mm_store_si128(reinterpret_cast<__m128i*>(bin), bn.bins_of(refs[i]));
        for (int a = 0; a < 3; ++a) {
          box[a * nb + bin[a]].extend(refs[i].box);
          ++count[a * nb + bin[a]];
        }
      }
      for (int a = 0; a < 3; ++a)
        for (int k = 0; k < nb; ++k) {
          ASSERT_EQ(bins->count[a][k], count[a * nb + k]) << a << " " << k;
          if (!count[a * nb + k]) continue;
          const Box4 got = bins->box(a, k), want = box[a * nb + k];
          ASSERT_EQ(got.aabb().lo, want.aabb().lo) << a << " " << k;
          ASSERT_EQ(got.aabb().hi, want.aabb().hi) << a << " " << k;
          ASSERT_EQ(got.max_ref_half_area(), want.max_ref_half_area()) << a << " " << k;
        }
    }
  }
}

TEST(BvhBuilders, SweepIsNoWorseThanBinnedAndLbvhNoBetter) {
  // The full sweep evaluates a superset of the binned candidates at each
  // node; LBVH ignores the SAH. Compared on a clustered scene.
  const test::NamedMesh s = test::soup(4000, 31);
  const double binned = tree_sah_cost(build_with("binned", s.mesh).nodes);
  const double sweep = tree_sah_cost(build_with("sweep", s.mesh).nodes);
  const double lbvh = tree_sah_cost(build_with("lbvh", s.mesh).nodes);
  EXPECT_LE(sweep, binned * 1.01);
  EXPECT_GT(lbvh, sweep);
}

// Triangles that coincide (the same three vertices, as in real meshes with
// doubled faces) have one centroid, so no object split separates them; a
// spatial split cannot either (every plane puts all of them on both sides).
// With single-triangle binary leaves such a node must still end in a
// median split, not in spatial splits that copy every reference into both
// children until the duplication budget is spent (it was: 1.5 references per
// triangle, twice the memory, on sponza and dragon_in_sponza).
TEST(BvhSbvh, CoincidentTrianglesDoNotSpendTheSplitBudget) {
  test::NamedMesh s = test::soup(300, 47, 3.0f);
  TriangleMesh dup;
  dup.vertices = {Vec3f(0.1f, 0.2f, 0.3f), Vec3f(0.9f, 0.25f, 0.35f), Vec3f(0.4f, 0.8f, 0.3f)};
  for (int i = 0; i < 12; ++i) dup.triangles.push_back({0, 1, 2});
  s.mesh.append(dup);
  const Prims p = prims_of(s.mesh);
  SbvhOptions so;
  so.base.leaf_threshold = 1;
  so.alpha = 1.0f;  // spatial splits only where no object split exists
  so.split_budget = 0.5f;
  SbvhStats st;
  const BinaryBvh t = build_sbvh(p.boxes, p.centroids, TriangleSplitter(s.mesh), so, &st);
  check_binary_tree(t, s.mesh, true);
  EXPECT_EQ(st.spatial_splits, 0u);
  EXPECT_EQ(t.prim_ids.size(), s.mesh.num_triangles());
}

// Points of every triangle (its vertices and 197 random ones) that lie in
// none of the boxes given for it: 0 when the boxes cover their triangles.
size_t uncovered_points(const TriangleMesh& mesh, std::map<uint32_t, std::vector<Aabb>>& boxes_of) {
  Pcg32 rng(5, 7);
  size_t uncovered = 0;
  for (uint32_t prim = 0; prim < mesh.num_triangles(); ++prim) {
    const Vec3f a = mesh.vertex(prim, 0), b = mesh.vertex(prim, 1), c = mesh.vertex(prim, 2);
    for (int i = 0; i < 200; ++i) {
      float u = rng.uniform(), v = rng.uniform();
      if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
      if (i < 3) u = i == 1, v = i == 2;  // the vertices themselves
      // Points are rounded in float; allow that rounding.
      const Vec3f q = (1.0f - u - v) * a + u * b + v * c;
      const float tol = 4e-7f * q.cwiseAbs().maxCoeff() + 1e-30f;
      bool covered = false;
      for (const Aabb& box : boxes_of[prim])
        covered |= (q.array() >= box.lo.array() - tol).all() && (q.array() <= box.hi.array() + tol).all();
      uncovered += !covered;
    }
  }
  return uncovered;
}

TEST(BvhSbvh, ReferencesCoverTheirTriangles) {
  // Long thin triangles across a box: the case spatial splits exist for.
  const test::NamedMesh s = test::soup(300, 47, 3.0f);
  const Prims p = prims_of(s.mesh);
  SbvhOptions so;
  so.alpha = 0.0f;
  so.split_budget = 1.0f;
  so.spatial_bins = 16;
  SbvhStats st;
  const BinaryBvh t = build_sbvh(p.boxes, p.centroids, TriangleSplitter(s.mesh), so, &st);
  EXPECT_GT(st.spatial_splits, 10u) << "the scene must exercise spatial splits";
  EXPECT_GT(t.prim_ids.size(), s.mesh.num_triangles());
  EXPECT_LE(t.prim_ids.size(), 2 * s.mesh.num_triangles()) << "split budget";
  check_binary_tree(t, s.mesh, true);
  // Every point of every triangle lies in the box of one of its references.
  std::map<uint32_t, std::vector<Aabb>> boxes_of;
  for (const Bvh2Node& n : t.nodes)
    if (is_leaf(n))
      for (uint32_t k = n.index; k < n.index + n.count; ++k) boxes_of[t.prim_ids[k]].push_back(n.bounds());
  EXPECT_EQ(uncovered_points(s.mesh, boxes_of), 0u);
}


TEST(BvhSbvh, SplitterBoxesEncloseTheExactCrossing) {
  const test::NamedMesh s = test::soup(200, 53, 2.0f);
  const TriangleSplitter split(s.mesh);
  Pcg32 rng(11, 3);
  size_t crossings = 0;
  for (uint32_t prim = 0; prim < s.mesh.num_triangles(); ++prim) {
    const Aabb box = s.mesh.triangle_bounds(prim);
    for (int axis = 0; axis < 3; ++axis) {
      const float pos = box.lo[axis] + rng.uniform() * (box.hi[axis] - box.lo[axis]);
      Aabb l, r;
      split.split(prim, box, axis, pos, true, l, r);
      EXPECT_TRUE(box.contains(l) && box.contains(r));
      // Each edge crossing the plane, in double precision, lies in both boxes.
      for (int e = 0; e < 3; ++e) {
        const Vec3f p = s.mesh.vertex(prim, e), q = s.mesh.vertex(prim, (e + 1) % 3);
        if (!((p[axis] < pos && q[axis] > pos) || (p[axis] > pos && q[axis] < pos))) continue;
        ++crossings;
        const double t = (static_cast<double>(pos) - p[axis]) / (static_cast<double>(q[axis]) - p[axis]);
        for (int a = 0; a < 3; ++a) {
          const double x = a == axis ? pos : p[a] + t * (static_cast<double>(q[a]) - p[a]);
          EXPECT_LE(l.lo[a], x);
          EXPECT_GE(l.hi[a], x);
          EXPECT_LE(r.lo[a], x);
          EXPECT_GE(r.hi[a], x);
        }
      }
      for (int c = 0; c < 3; ++c) {
        const Vec3f v = s.mesh.vertex(prim, c);
        if (v[axis] <= pos) {
          EXPECT_TRUE(l.contains(v));
        }
        if (v[axis] >= pos) {
          EXPECT_TRUE(r.contains(v));
        }
      }
    }
  }
  EXPECT_GT(crossings, 100u);
}



// A build reference carries its box's half area in lane 3 of hi, computed as
// Box4::half_area computes it, and a union of references' boxes carries the
// largest: the size split skips its pass over a node's references on it.
TEST(BvhBinned, ReferenceBoxesCarryTheirLargestHalfArea) {
  const Aabb a(Vec3f(0, 0, 0), Vec3f(1, 2, 3)), b(Vec3f(5, 5, 5), Vec3f(5.5f, 5, 7)), flat(Vec3f(1, 1, 1), Vec3f(1, 1, 4));
  const BuildRef ra = BuildRef::make(a, a.center(), 0), rb = BuildRef::make(b, b.center(), 1),
                 rf = BuildRef::make(flat, flat.center(), 2);
  EXPECT_EQ(ra.box.max_ref_half_area(), ra.box.half_area());
  EXPECT_EQ(ra.box.max_ref_half_area(), 11.0f);
  EXPECT_EQ(rb.box.max_ref_half_area(), 1.0f);
  EXPECT_EQ(rf.box.max_ref_half_area(), 0.0f);
  EXPECT_EQ(merge(rb.box, ra.box).max_ref_half_area(), 11.0f);
  EXPECT_EQ(merge(rf.box, rb.box).max_ref_half_area(), 1.0f);
  EXPECT_EQ(merge(ra.box, rb.box).half_area(), Box4::from(Aabb(Vec3f(0, 0, 0), Vec3f(5.5f, 5, 7))).half_area());
  EXPECT_EQ(Box4::from(a).max_ref_half_area(), 0.0f) << "boxes not made from references carry 0";
  // A denormal area is stored as the smallest normal float: still a bound.
  const Aabb tiny(Vec3f(0, 0, 0), Vec3f(1e-20f, 1e-20f, 0));
  const BuildRef rt = BuildRef::make(tiny, tiny.center(), 3);
  EXPECT_GT(rt.box.half_area(), 0.0f);
  EXPECT_LT(rt.box.half_area(), std::numeric_limits<float>::min());
  EXPECT_EQ(rt.box.max_ref_half_area(), std::numeric_limits<float>::min());
  // The bins keep the largest too (the children's boxes come from them).
  Box4 cbounds;
  for (const BuildRef* r : {&ra, &rb, &rf}) cbounds.extend(r->centroid());
  const sah::Binning bn(cbounds, 4);
  const BuildRef refs[] = {ra, rb, rf};
  const auto bins = sah::bin_refs(refs, 0, 3, bn, 4);
  float largest = 0.0f;
  for (int bin = 0; bin < 4; ++bin)
    if (bins->count[0][bin]) largest = std::max(largest, bins->box(0, bin).max_ref_half_area());
  EXPECT_EQ(largest, 11.0f);
}

// One thread and the default pool give the same binned tree, node for node
// (the pool's subtree tasks number their nodes as they run; the build
// renumbers them as the serial build does), and so do two runs of the pool:
// the one-thread path partitions large nodes in one pass (the split's left
// count placing the right side), the parallel one counts per chunk first;
// both are stable. The same for the accelerator's whole build, reinsertion
// (whose ties follow the numbering) and layout included.
TEST(BvhBinned, OneThreadAndThePoolBuildTheSameTree) {
  test::NamedMesh s = test::soup(40000, 31, 0.02f);
  const Prims p = prims_of(s.mesh);
  BuildOptions bo;
  bo.big_node = 0.1f;
  bo.big_root = 0.03f;
  bo.leaf_threshold = 1;
  const BinaryBvh pool = build_binned_sah(p.boxes, p.centroids, bo);
  const BinaryBvh pool2 = build_binned_sah(p.boxes, p.centroids, bo);
  BinaryBvh serial;
  BuildStats serial_stats;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    serial = build_binned_sah(p.boxes, p.centroids, bo);
    serial_stats = make_accelerator("bvh:preset=quality")->build(s.mesh);
  }
  check_binary_tree(serial, s.mesh, false);
  for (const BinaryBvh* t : {&pool, &pool2}) {
    ASSERT_EQ(serial.nodes.size(), t->nodes.size());
    EXPECT_EQ(serial.prim_ids, t->prim_ids);
    for (size_t i = 0; i < t->nodes.size(); ++i) {
      ASSERT_EQ(serial.nodes[i].index, t->nodes[i].index) << i;
      ASSERT_EQ(serial.nodes[i].count, t->nodes[i].count) << i;
      ASSERT_EQ(serial.nodes[i].bounds().lo, t->nodes[i].bounds().lo) << i;
      ASSERT_EQ(serial.nodes[i].bounds().hi, t->nodes[i].bounds().hi) << i;
    }
  }
  const BuildStats pool_stats = make_accelerator("bvh:preset=quality")->build(s.mesh);
  EXPECT_EQ(pool_stats.extra.at("opt_moves"), serial_stats.extra.at("opt_moves"));
  // (a parallel sum: equal up to the order of its additions)
  EXPECT_NEAR(pool_stats.extra.at("sah_tree"), serial_stats.extra.at("sah_tree"),
              1e-9 * serial_stats.extra.at("sah_tree"));
  EXPECT_EQ(pool_stats.nodes, serial_stats.nodes);
  EXPECT_EQ(pool_stats.bytes, serial_stats.bytes);
}

// big / bigroot (BuildOptions::big_node, big_root): a node's references whose
// boxes are large against its own (or the root's) become one child, the rest
// the other; nothing else about the tree changes.
TEST(BvhBinned, LargeReferencesGetAChildOfTheirOwn) {
  // Small triangles filling the unit cube, a floor and a wall across it.
  test::NamedMesh s = test::soup(3000, 29, 0.05f);
  const uint32_t first_large = static_cast<uint32_t>(s.mesh.num_triangles());
  TriangleMesh large;
  large.vertices = {Vec3f(-0.1f, 0.5f, -0.1f), Vec3f(1.1f, 0.5f, -0.1f), Vec3f(1.1f, 0.5f, 1.1f),
                    Vec3f(-0.1f, 0.5f, 1.1f),  Vec3f(0.3f, -0.1f, -0.1f), Vec3f(0.3f, 1.1f, -0.1f),
                    Vec3f(0.3f, 1.1f, 1.1f),   Vec3f(0.3f, -0.1f, 1.1f)};
  large.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  s.mesh.append(large);
  const Prims p = prims_of(s.mesh);
  // The triangles under a node.
  auto triangles_under = [](const BinaryBvh& t, uint32_t node) {
    std::vector<uint32_t> out, stack{node};
    while (!stack.empty()) {
      const Bvh2Node& n = t.nodes[stack.back()];
      stack.pop_back();
      if (is_leaf(n)) {
        for (uint32_t k = n.index; k < n.index + n.count; ++k) out.push_back(t.prim_ids[k]);
      } else {
        stack.push_back(n.index);
        stack.push_back(n.index + 1);
      }
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  const std::vector<uint32_t> large_ids{first_large, first_large + 1, first_large + 2, first_large + 3};
  for (int rule = 0; rule < 3; ++rule) {
    SCOPED_TRACE(rule == 0 ? "off" : rule == 1 ? "big_node" : "big_root");
    BuildOptions bo;
    bo.big_node = rule == 1 ? 0.1f : 0.0f;
    bo.big_root = rule == 2 ? 0.1f : 0.0f;
    bo.big_min = 1024;
    const BinaryBvh t = build_binned_sah(p.boxes, p.centroids, bo);
    check_binary_tree(t, s.mesh, false);
    ASSERT_FALSE(is_leaf(t.nodes[0]));
    const std::vector<uint32_t> left = triangles_under(t, t.nodes[0].index);
    if (rule == 0) EXPECT_NE(left, large_ids) << "centroid splits do not separate by size";
    else EXPECT_EQ(left, large_ids) << "the floor and the wall, and only they, under the root's first child";
  }
  // Only at nodes of at least big_min references.
  BuildOptions few;
  few.big_node = 0.1f;
  few.big_min = 4000;
  BinnedBuildStats few_stats;
  EXPECT_NE(triangles_under(build_binned_sah(p.boxes, p.centroids, few, &few_stats), 1), large_ids);
  EXPECT_EQ(few_stats.big_splits, 0u);
  // More than a quarter of a node's references large: ordinary splits only.
  test::NamedMesh longs = test::soup(1200, 7, 3.0f);
  const Prims lp = prims_of(longs.mesh);
  BuildOptions all;
  all.big_node = 1e-6f;
  all.big_min = 16;
  BinnedBuildStats all_stats;
  check_binary_tree(build_binned_sah(lp.boxes, lp.centroids, all, &all_stats), longs.mesh, false);
  EXPECT_EQ(all_stats.big_splits, 0u);
  // Through the spec: on with the binned builder (the family's brute-force
  // test checks the hits), off with the others.
  const BuildStats split = make_accelerator("bvh:opt=none")->build(s.mesh);
  EXPECT_GE(split.extra.at("big_splits"), 1.0);
  EXPECT_EQ(make_accelerator("bvh:opt=none,builder=sweep")->build(s.mesh).extra.count("big_splits"), 0u);
}

TEST(BvhLbvh, CoincidentCentroidsGiveABalancedTree) {
  // 4096 triangles with the very same box centre (rotated copies), and
  // Morton codes that all collide: the index breaks the ties.
  TriangleMesh m;
  const int n = 4096;
  for (int i = 0; i < n; ++i) {
    const float a = 6.2831853f * static_cast<float>(i) / n;
    const uint32_t base = static_cast<uint32_t>(m.vertices.size());
    m.vertices.push_back(Vec3f(std::cos(a), std::sin(a), 0.0f));
    m.vertices.push_back(Vec3f(-std::cos(a), -std::sin(a), 0.0f));
    m.vertices.push_back(Vec3f(0.0f, 0.0f, 1.0f + 0.0001f * static_cast<float>(i % 7)));
    m.vertices.push_back(Vec3f(0.0f, 0.0f, -1.0f - 0.0001f * static_cast<float>(i % 7)));
    m.triangles.push_back({base, base + 1, base + 2});
    m.triangles.push_back({base + 1, base, base + 3});
  }
  const Prims p = prims_of(m);
  const BinaryBvh t = build_lbvh(p.boxes, p.centroids);
  check_binary_tree(t, m, false);
  const Bvh2Shape shape = measure_tree(t.nodes);
  EXPECT_LE(shape.max_depth, 2 + static_cast<int>(std::ceil(std::log2(2.0 * n)))) << "ties split by index";
  // And the accelerator built on it answers like brute force.
  auto a = make_accelerator("bvh:builder=lbvh");
  auto brute = make_accelerator("brute");
  a->build(m);
  brute->build(m);
  Pcg32 rng(3, 9);
  for (int i = 0; i < 300; ++i) {
    const Ray r(Vec3f(2.0f * rng.uniform() - 1.0f, 2.0f * rng.uniform() - 1.0f, 3.0f), Vec3f(0.01f, 0.02f, -1.0f));
    const Hit x = a->intersect1(r), y = brute->intersect1(r);
    ASSERT_EQ(x.valid(), y.valid());
    if (x.valid()) {
      EXPECT_EQ(x.t, y.t);
    }
  }
}

TEST(BvhLbvh, MortonSpreadPlacesBitsEveryThird) {
  EXPECT_EQ(morton_spread21(0), 0u);
  EXPECT_EQ(morton_spread21(1), 1u);
  EXPECT_EQ(morton_spread21(2), 8u);
  EXPECT_EQ(morton_spread21(0x1FFFFF), 0x1249249249249249ull);
  for (int bit = 0; bit < 21; ++bit) EXPECT_EQ(morton_spread21(1u << bit), 1ull << (3 * bit));
  EXPECT_EQ(morton_spread21(1u << 21), 0u) << "only 21 bits are used";
}

}  // namespace
}  // namespace raylab
