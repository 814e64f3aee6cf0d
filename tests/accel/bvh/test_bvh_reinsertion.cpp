// Post-build optimisation by subtree reinsertion (optimize_reinsertion.h):
// lower SAH cost within the time budget, the light default, incremental
// measurement, selecting the largest keys.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "accel/bvh/build_binned_sah.h"
#include "accel/bvh/build_lbvh.h"
#include "accel/bvh/optimize_reinsertion.h"
#include "accel/registry.h"
#include "base/mesh_shapes.h"
#include "base/pcg.h"
#include "tests/accel/bvh/bvh_test_util.h"
#include "tests/accel_test_util.h"

namespace raylab {
namespace {

using test::Prims;
using test::prims_of;
using test::check_binary_tree;

TEST(BvhReinsertion, LowersSahCostAndRespectsTheTimeBudget) {
  const test::NamedMesh s{"sphere", make_uv_sphere(96, 48)};  // a surface: LBVH leaves room to improve
  const Prims p = prims_of(s.mesh);
  const BinaryBvh base = build_lbvh(p.boxes, p.centroids);
  ReinsertionStats st;
  const BinaryBvh opt = optimize_reinsertion(base, ReinsertionOptions{}, &st);
  check_binary_tree(opt, s.mesh, false);
  EXPECT_NEAR(st.sah_before, tree_sah_cost(base.nodes), 1e-3 * st.sah_before);
  EXPECT_NEAR(st.sah_after, tree_sah_cost(opt.nodes), 1e-3 * st.sah_after);
  EXPECT_LT(st.sah_after, 0.98 * st.sah_before);
  EXPECT_GT(st.moves, 0u);
  // No rounds, no change.
  ReinsertionOptions none;
  none.max_rounds = 0;
  ReinsertionStats st0;
  const BinaryBvh same = optimize_reinsertion(base, none, &st0);
  EXPECT_EQ(st0.rounds, 0);
  EXPECT_EQ(st0.moves, 0u);
  EXPECT_NEAR(tree_sah_cost(same.nodes), st.sah_before, 1e-6 * st.sah_before);
  // Reported by the accelerator.
  auto a = make_accelerator("bvh:builder=lbvh,opt=reinsert");
  const BuildStats bs = a->build(s.mesh);
  ASSERT_TRUE(bs.extra.count("sah_before_opt") && bs.extra.count("sah_after_opt"));
  EXPECT_LT(bs.extra.at("sah_after_opt"), bs.extra.at("sah_before_opt"));
}

// The light pass (the default) and the full reinsertion differ in rounds,
// batch and binary leaves (BvhConfig, test_bvh_config.cpp): the light pass
// starts from the tree without it and lowers its SAH cost, the full one
// lowers it further.
TEST(BvhReinsertion, LightPassBetweenNoneAndTheFullPass) {
  const test::NamedMesh s = test::soup(3000, 5);
  auto stats_of = [&](const char* spec) {
    auto a = make_accelerator(spec);
    return a->build(s.mesh);
  };
  const BuildStats light = stats_of("bvh"), none = stats_of("bvh:opt=none"), full = stats_of("bvh:opt=reinsert");
  EXPECT_GE(light.extra.at("opt_rounds"), 1.0);
  EXPECT_LE(light.extra.at("opt_rounds"), 4.0);
  EXPECT_GT(light.extra.at("opt_moves"), 0.0);
  EXPECT_GT(full.extra.at("opt_moves"), light.extra.at("opt_moves"));
  EXPECT_EQ(none.extra.count("opt_rounds"), 0u);
  EXPECT_LT(light.extra.at("sah_tree"), light.extra.at("sah_before_opt"));
  EXPECT_LT(full.extra.at("sah_tree"), light.extra.at("sah_tree"));
  for (const char* bad : {"bvh:opt=heavy", "bvh:opt_batch=0.1", "bvh:opt_rounds=4"})
    EXPECT_THROW(make_accelerator(bad), SpecError) << bad;
}

// Each round re-measures only the nodes the last round's moves changed
// (relinked, refit, or all when the root moved): the same trees as
// measuring every node every round, on meshes, builders and batch sizes
// where many rounds apply many moves.
TEST(BvhReinsertion, IncrementalMeasureGivesTheSameTree) {
  const test::NamedMesh soup = test::soup(4000, 11), big = test::soup(1500, 4, 6.0f);
  for (const TriangleMesh* m : {&soup.mesh, &big.mesh})
    for (const char* b : {"binned", "lbvh"})
      for (double batch : {0.005, 0.05, 0.3}) {
        const Prims p = prims_of(*m);
        BuildOptions bo;
        bo.leaf_threshold = 2;
        const BinaryBvh base = std::string(b) == "lbvh" ? build_lbvh(p.boxes, p.centroids)
                                                         : build_binned_sah(p.boxes, p.centroids, bo);
        ReinsertionOptions fast, full;
        fast.max_rounds = full.max_rounds = 12;
        fast.batch_fraction = full.batch_fraction = batch;
        fast.min_gain = full.min_gain = 0.0;
        full.remeasure_all = true;
        ReinsertionStats sf, sa;
        const BinaryBvh a = optimize_reinsertion(base, fast, &sf), c = optimize_reinsertion(base, full, &sa);
        SCOPED_TRACE(fmt::format("{} batch {}", b, batch));
        if (batch >= 0.05) {
          EXPECT_GT(sf.moves, 0u);
        }
        EXPECT_EQ(sf.moves, sa.moves);
        EXPECT_EQ(sf.rounds, sa.rounds);
        ASSERT_EQ(a.nodes.size(), c.nodes.size());
        EXPECT_EQ(a.prim_ids, c.prim_ids);
        for (size_t i = 0; i < a.nodes.size(); ++i)
          EXPECT_EQ(std::memcmp(&a.nodes[i], &c.nodes[i], sizeof(Bvh2Node)), 0) << "node " << i;
      }
}

// A round's candidates: the k largest non-zero keys, ties by the lower
// index, as a full sort would pick them, with keys spread over many
// histogram buckets, crowded into one, tiny (below the histogram's first
// bucket) and zero, and k below, at and above the number of non-zero keys.
TEST(BvhReinsertion, SelectsTheLargestKeysAsASortWould) {
  auto reference = [](const std::vector<uint32_t>& keys, size_t k) {
    std::vector<uint32_t> idx;
    for (uint32_t i = 0; i < keys.size(); ++i)
      if (keys[i]) idx.push_back(i);
    std::sort(idx.begin(), idx.end(), [&](uint32_t a, uint32_t b) { return keys[a] != keys[b] ? keys[a] > keys[b] : a < b; });
    idx.resize(std::min(k, idx.size()));
    std::sort(idx.begin(), idx.end());
    return idx;
  };
  auto bits = [](float v) {
    uint32_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
  };
  Pcg32 rng(42, 7);
  std::vector<std::vector<uint32_t>> cases;
  std::vector<uint32_t> spread, crowded, tiny, mixed;
  for (int i = 0; i < 5000; ++i) {
    spread.push_back(bits(std::ldexp(rng.uniform() + 0.5f, static_cast<int>(rng.uniform() * 60.0f) - 30)));
    crowded.push_back(i % 7 == 0 ? 0u : bits(1.0f + 0.01f * rng.uniform()));  // one bucket, many equal keys
    tiny.push_back(i % 3 == 0 ? 0u : 1u + static_cast<uint32_t>(rng.uniform() * 1000.0f));
    mixed.push_back(i % 2 ? bits(static_cast<float>(i % 13)) : 0u);
  }
  cases = {spread, crowded, tiny, mixed, std::vector<uint32_t>(100, 0u), {}};
  for (size_t c = 0; c < cases.size(); ++c)
    for (size_t k : {size_t{0}, size_t{1}, size_t{17}, size_t{500}, size_t{2500}, size_t{4300}, size_t{6000}}) {
      std::vector<uint32_t> got;
      select_largest_keys(cases[c], k, got);
      std::sort(got.begin(), got.end());
      EXPECT_EQ(got, reference(cases[c], k)) << "case " << c << " k " << k;
    }
}

}  // namespace
}  // namespace raylab
