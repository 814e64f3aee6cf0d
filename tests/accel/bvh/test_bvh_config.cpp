// `bvh`'s parameters and presets (accel/bvh/bvh_config.h): declared once,
// the registry's list is the declaration, the defaults reach the config,
// every preset is a set of declared values that a given parameter overrides,
// and the settings derived from the parameters are the measured ones.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>
#include <tuple>

#include "accel/bvh/bvh_config.h"
#include "accel/core/simd/simd.h"
#include "accel/registry.h"
#include "tests/accel_test_util.h"

namespace raylab {
namespace {

BvhConfig config_of(const std::string& spec) {
  return bvh_config(Params("bvh", bvh_parameters(), Spec::parse(spec).params));
}

auto fields(const BvhConfig& c) {
  return std::make_tuple(c.builder, c.opt, c.layout, c.leaf, c.bins, c.split_budget, c.spatial_min, c.node_cost,
                         c.block_cost, c.tri, c.packet, c.bound, c.simd, c.binary_leaf, c.opt_rounds, c.opt_batch,
                         c.big_node, c.big_root, c.thick_limit);
}

TEST(BvhConfig, TheRegistryListsTheDeclarationOnce) {
  const auto declared = bvh_parameters();
  const auto& listed = accelerator_info("bvh").params;
  ASSERT_EQ(listed.size(), declared.size());
  std::set<std::string> names;
  for (size_t i = 0; i < declared.size(); ++i) {
    EXPECT_EQ(listed[i].name, declared[i].name);
    EXPECT_EQ(listed[i].default_value, declared[i].default_value);
    EXPECT_FALSE(declared[i].help.empty()) << declared[i].name;
    EXPECT_TRUE(declared[i].check.accepts(declared[i].default_value)) << declared[i].name;
    names.insert(declared[i].name);
  }
  EXPECT_EQ(names.size(), declared.size()) << "a parameter declared twice";
  EXPECT_LE(declared.size(), 15u);
}

TEST(BvhConfig, DefaultsComeFromTheDeclaration) {
  const BvhConfig c = config_of("bvh");
  EXPECT_EQ(c.preset, BvhPreset::Default);
  EXPECT_EQ(c.builder, BvhBuilder::Binned);
  EXPECT_EQ(c.opt, BvhOpt::Light);
  EXPECT_EQ(c.layout, simd::isa_bits() >= 512 ? BvhLayout::Bvh16 : BvhLayout::Bvh8);
  EXPECT_EQ(c.leaf, 2 * kBvhBlockWidth);
  EXPECT_EQ(c.bins, 64);
  EXPECT_EQ(c.split_budget, 0.5f);
  EXPECT_EQ(c.spatial_min, 0);
  EXPECT_EQ(c.node_cost, 2.0f);
  EXPECT_EQ(c.block_cost, 1.0f);
  EXPECT_EQ(c.tri, TriangleTest::Watertight);
  EXPECT_EQ(c.packet, 0);
  EXPECT_EQ(c.bound, BvhBound::Box);
  EXPECT_TRUE(c.simd);
  // A declared default changed in the spec reaches its field.
  EXPECT_EQ(config_of("bvh:bins=16").bins, 16);
  EXPECT_EQ(config_of("bvh:leaf=5").leaf, 5);
  EXPECT_EQ(config_of("bvh:layout=bvh2").leaf, 4);
  EXPECT_EQ(config_of("bvh:bound=sphere").layout, BvhLayout::Bvh2);
  EXPECT_EQ(config_of("bvh:tri=mt").tri, TriangleTest::MollerTrumbore);
  EXPECT_FALSE(config_of("bvh:simd=0").simd);
  EXPECT_EQ(config_of("bvh:builder=lbvh").builder, BvhBuilder::Lbvh);
}

// A preset is its assignments: the same config as writing them out, checked
// by the declaration, and any parameter given beside it wins.
TEST(BvhConfig, PresetsAreDeclaredValuesThatAGivenParameterOverrides) {
  const auto declared = bvh_parameters();
  std::set<std::string> names;
  for (const BvhPresetInfo& pr : bvh_presets()) {
    names.insert(pr.name);
    const Spec explicit_spec = Spec::parse(std::string("bvh") + (*pr.params ? ":" : "") + pr.params);
    for (const auto& [key, value] : explicit_spec.params) {
      const std::string& name = key;  // (clang 14 does not capture structured bindings)
      const auto it = std::find_if(declared.begin(), declared.end(), [&](const ParamInfo& p) { return p.name == name; });
      ASSERT_NE(it, declared.end()) << pr.name << ": " << key;
      EXPECT_TRUE(it->check.accepts(value)) << pr.name << ": " << key << "=" << value;
    }
    EXPECT_EQ(fields(config_of(std::string("bvh:preset=") + pr.name)), fields(config_of(explicit_spec.to_string())))
        << pr.name;
    EXPECT_NE(declared[0].help.find(pr.name), std::string::npos) << "the preset help names " << pr.name;
  }
  EXPECT_EQ(names, (std::set<std::string>{"fast", "default", "quality", "sbvh"}));
  EXPECT_EQ(fields(config_of("bvh:preset=default")), fields(config_of("bvh")));
  EXPECT_EQ(config_of("bvh:preset=quality").opt, BvhOpt::Reinsert);
  EXPECT_EQ(config_of("bvh:preset=quality,opt=none").opt, BvhOpt::None);
  EXPECT_EQ(config_of("bvh:preset=sbvh,smin=10").spatial_min, 10);
  EXPECT_EQ(config_of("bvh:preset=sbvh,builder=binned").builder, BvhBuilder::Binned);
  EXPECT_EQ(config_of("bvh:preset=fast").opt, BvhOpt::None);
  EXPECT_THROW(config_of("bvh:preset=fastest"), SpecError);
}

// The settings that follow from the parameters: binary leaves and the
// reinsertion's work by opt, the size split with the binned builder only,
// the thick-leaf limit on 16-wide light-pass trees only.
TEST(BvhConfig, DerivedSettingsFollowTheParameters) {
  const BvhConfig none = config_of("bvh:opt=none"), light = config_of("bvh"), full = config_of("bvh:opt=reinsert");
  EXPECT_EQ(std::tie(none.binary_leaf, light.binary_leaf, full.binary_leaf), std::make_tuple(4, 3, 1));
  EXPECT_EQ(std::tie(light.opt_rounds, light.opt_batch), std::make_tuple(4, 0.005));
  EXPECT_EQ(std::tie(full.opt_rounds, full.opt_batch), std::make_tuple(32, 0.15));
  EXPECT_EQ(std::tie(light.big_node, light.big_root), std::make_tuple(0.1f, 0.03f));
  for (const char* other : {"bvh:builder=sweep", "bvh:builder=sbvh", "bvh:builder=lbvh"}) {
    const BvhConfig c = config_of(other);
    EXPECT_EQ(std::tie(c.big_node, c.big_root), std::make_tuple(0.0f, 0.0f)) << other;
  }
  EXPECT_EQ(config_of("bvh:layout=bvh16").thick_limit, 0.4f);
  EXPECT_EQ(config_of("bvh:layout=bvh16,opt=none").thick_limit, 0.4f);
  EXPECT_EQ(config_of("bvh:layout=bvh16,opt=reinsert").thick_limit, 0.0f);
  EXPECT_EQ(config_of("bvh:layout=bvh8").thick_limit, 0.0f);
  EXPECT_EQ(config_of("bvh:layout=bvh4").thick_limit, 0.0f);
}

// Through the accelerator: a preset builds the tree of its written-out spec.
TEST(BvhConfig, PresetsBuildTheTreesOfTheirParameters) {
  const test::NamedMesh s = test::soup(3000, 7);
  const auto tree_of = [&](const std::string& spec) {
    const BuildStats st = make_accelerator(spec)->build(s.mesh);
    return std::make_tuple(st.nodes, st.leaves, st.bytes, st.max_depth, st.sah_cost);
  };
  for (const BvhPresetInfo& pr : bvh_presets())
    EXPECT_EQ(tree_of(std::string("bvh:preset=") + pr.name), tree_of(std::string("bvh") + (*pr.params ? ":" : "") + pr.params))
        << pr.name;
  EXPECT_NE(tree_of("bvh:preset=fast"), tree_of("bvh"));
  EXPECT_NE(tree_of("bvh:preset=quality"), tree_of("bvh"));
}

}  // namespace
}  // namespace raylab
