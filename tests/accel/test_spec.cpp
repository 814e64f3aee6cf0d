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

// Declared valid values: the checker's verdicts at and beside each bound,
// and the one message shape ("OWNER: KEY must be VALID, got VALUE").
TEST(ParamCheck, AcceptsExactlyTheDeclaredValues) {
  const ParamCheck bins = integer_in(2, 64).or_number(0);
  EXPECT_EQ(bins.describe(), "0 or in 2..64");
  for (const char* v : {"0", "2", "64"}) EXPECT_TRUE(bins.accepts(v)) << v;
  for (const char* v : {"1", "65", "-1", "2.5", "abc", "", "+2", "1e1"}) EXPECT_FALSE(bins.accepts(v)) << v;

  const ParamCheck density = real_in(0, 64, Ends::OpenLow);
  EXPECT_EQ(density.describe(), "in (0, 64]");
  for (const char* v : {"64", "1e-30", "0.5"}) EXPECT_TRUE(density.accepts(v)) << v;
  for (const char* v : {"0", "-0", "64.0001", "nan", "inf", "x"}) EXPECT_FALSE(density.accepts(v)) << v;
  EXPECT_EQ(real_in(0, 1, Ends::OpenHigh).describe(), "in [0, 1)");
  EXPECT_FALSE(real_in(0, 1, Ends::OpenHigh).accepts("1"));
  EXPECT_EQ(real_in(0, kUnbounded, Ends::OpenLow).describe(), "> 0");
  EXPECT_EQ(integer_in(1, kUnbounded).describe(), ">= 1");
  EXPECT_EQ(integer_in(-kUnbounded, kUnbounded).describe(), "a whole number");
  // as_float: the value the factory stores (a float) is checked.
  EXPECT_TRUE(real_in(0, kUnbounded, Ends::OpenLow).accepts("1e39"));
  EXPECT_FALSE(real_in(0, kUnbounded, Ends::Open).as_float().accepts("1e39"));  // overflows to infinity
  EXPECT_TRUE(real_in(0, kUnbounded).as_float().accepts("1e39"));              // closed: infinity included
  EXPECT_FALSE(real_in(0, kUnbounded, Ends::Open).as_float().accepts("1e-50"));  // rounds to 0
  EXPECT_TRUE(real_in(0, 4).as_float().accepts("-1e-50"));                      // rounds to -0
  EXPECT_EQ(real_in(0, kUnbounded, Ends::Open).describe(), "> 0");

  EXPECT_EQ(integer_of({3, 7, 13}).describe(), "3, 7 or 13");
  EXPECT_FALSE(integer_of({3, 7, 13}).accepts("5"));
  EXPECT_EQ(integer_in(0, 64).or_word("auto").describe(), "auto or in 0..64");
  EXPECT_TRUE(integer_in(0, 64).or_word("auto").accepts("auto"));
  EXPECT_EQ(one_of({"box", "sphere"}).describe(), "box or sphere");
  EXPECT_FALSE(one_of({"box", "sphere"}).accepts("cone"));
  for (const char* v : {"0", "1", "true", "off", "yes"}) EXPECT_TRUE(boolean_flag().accepts(v)) << v;
  EXPECT_FALSE(boolean_flag().accepts("maybe"));

  try {
    make_accelerator("bsp:tplanes=65");
    FAIL() << "no exception";
  } catch (const SpecError& e) {
    EXPECT_STREQ(e.what(), "bsp: tplanes must be in 0..64, got 65");
  }
  try {
    make_accelerator("kdtree:max_depth=65");
    FAIL() << "no exception";
  } catch (const SpecError& e) {
    EXPECT_STREQ(e.what(), "kdtree: max_depth must be auto or in 0..64, got 65");
  }
  try {
    make_accelerator("bvh:bins=x");
    FAIL() << "no exception";
  } catch (const SpecError& e) {
    EXPECT_STREQ(e.what(), "bvh: bins must be in 2..256, got x (not an integer)");
  }
  EXPECT_THROW(load_scene("terrain:roughness=1"), SpecError);  // scenes declare theirs the same way
}

// The registry states every parameter's valid values (only res=AxBxC is
// free text, parsed by the grids), and every default is one of them.
TEST(Registry, EveryParameterDeclaresItsValidValues) {
  for (const auto& info : accelerator_registry())
    for (const auto& p : info.params) {
      EXPECT_TRUE(p.check.kind != ParamKind::Text || p.name == "res") << info.name << ":" << p.name;
      EXPECT_TRUE(p.check.accepts(p.default_value)) << info.name << ":" << p.name << "=" << p.default_value;
    }
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
