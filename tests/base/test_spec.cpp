// Spec strings ("name:key=value,...") and the declared valid values of a parameter
// (base/spec.h, base/param_check.h).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "base/param_check.h"
#include "base/spec.h"

namespace raylab {
namespace {

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

// Declared valid values: the checker's verdicts at and beside each bound
// (the message shape, "OWNER: KEY must be VALID, got VALUE", is the
// registry's: Registry.ParameterErrorsSayWhatIsValid).
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
}

}  // namespace
}  // namespace raylab
