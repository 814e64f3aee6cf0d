// Spec strings and the accelerator factory.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "accel/registry.h"
#include "scenes/scene_registry.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;

TEST(Spec, ParsesNameAndParameters) {
  const Spec s = Spec::parse("bvh:leaf=4,bins=16");
  EXPECT_EQ(s.name, "bvh");
  EXPECT_EQ(s.params.at("leaf"), "4");
  EXPECT_EQ(s.params.at("bins"), "16");
  EXPECT_EQ(s.to_string(), "bvh:bins=16,leaf=4");
  EXPECT_EQ(Spec::parse("embree").params.size(), 0u);
}

TEST(Spec, RejectsMalformedText) {
  EXPECT_THROW(Spec::parse(""), SpecError);
  EXPECT_THROW(Spec::parse(":leaf=4"), SpecError);
  EXPECT_THROW(Spec::parse("bvh:leaf"), SpecError);
  EXPECT_THROW(Spec::parse("bvh:leaf=4,leaf=5"), SpecError);
  EXPECT_THROW(Spec::parse("bvh:=4"), SpecError);
}

TEST(Spec, SplitsListsWithParameters) {
  EXPECT_THAT(split_spec_list("bvh:leaf=4,bins=16,brute,embree:robust=1"),
              ::testing::ElementsAre("bvh:leaf=4,bins=16", "brute", "embree:robust=1"));
  EXPECT_THAT(split_spec_list("bvh;brute"), ::testing::ElementsAre("bvh", "brute"));
}

TEST(Registry, UnknownNamesAndParametersListWhatExists) {
  try {
    make_accelerator(kReservedUnknownAccelerator);
    FAIL() << "no exception";
  } catch (const SpecError& e) {
    EXPECT_THAT(e.what(), HasSubstr(std::string("unknown accelerator '") + kReservedUnknownAccelerator + "'"));
    EXPECT_THAT(e.what(), HasSubstr("bvh"));
    EXPECT_THAT(e.what(), HasSubstr("embree"));
  }
  try {
    make_accelerator("bvh:leef=3");
    FAIL() << "no exception";
  } catch (const SpecError& e) {
    EXPECT_THAT(e.what(), HasSubstr("unknown parameter 'leef'"));
    EXPECT_THAT(e.what(), HasSubstr("leaf"));
  }
  EXPECT_THROW(make_accelerator("bvh:leaf=abc"), SpecError);
  EXPECT_THROW(make_accelerator("bvh:leaf=0"), SpecError);
  EXPECT_THROW(make_accelerator("embree:quality=ultra"), SpecError);
  EXPECT_THROW(make_accelerator("embree:robust=maybe"), SpecError);
}

TEST(Registry, AllExpandsToEveryAccelerator) {
  const auto all = expand_accelerator_list("all");
  EXPECT_EQ(all.size(), accelerator_registry().size());
  EXPECT_EQ(all.front(), "embree");
  EXPECT_THROW(expand_accelerator_list("bvh,nope"), SpecError);
  EXPECT_THROW(expand_accelerator_list(""), SpecError);
}

TEST(Registry, SweepReplacesTheParameterWhereDeclared) {
  const auto specs = apply_sweep({"embree", "bvh:bins=8"}, "leaf", {"1", "2"});
  EXPECT_THAT(specs, ::testing::ElementsAre("embree", "bvh:bins=8,leaf=1", "bvh:bins=8,leaf=2"));
  EXPECT_THROW(apply_sweep({"embree"}, "leaf", {"1"}), SpecError);
  EXPECT_THROW(apply_sweep({"bvh"}, "leaf", {"x"}), SpecError);
}

TEST(Registry, SpecOfCreatedAcceleratorIsCanonical) {
  EXPECT_EQ(make_accelerator("bvh:leaf=2,bins=8")->spec(), "bvh:bins=8,leaf=2");
}

TEST(SceneRegistry, UnknownScenesAndParametersAreErrors) {
  EXPECT_THROW(load_scene("nosuchscene"), SpecError);
  EXPECT_THROW(load_scene("soup:n=-5"), SpecError);
  EXPECT_THROW(load_scene("soup:q=1"), SpecError);
  EXPECT_THROW(load_scene("missing/file.ply"), std::runtime_error);
  EXPECT_EQ(load_scene("soup:n=123").num_triangles(), 123u);
  EXPECT_EQ(load_scene("cornell").num_triangles(), 32u);
}

}  // namespace
}  // namespace raylab
