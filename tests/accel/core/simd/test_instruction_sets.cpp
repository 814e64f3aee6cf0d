// The start-up instruction-set check (accel/core/simd/instruction_sets.h): its verdict on
// supplied feature sets, its message, and this build's list against the compiler's macros.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "accel/core/simd/instruction_sets.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;

TEST(InstructionSets, TheFirstExtensionTheCpuLacksIsNamed) {
  const std::vector<InstructionSet> compiled = {{"sse2", true}, {"avx", true}, {"avx2", false}, {"fma", false}};
  EXPECT_STREQ(first_missing_instruction_set(compiled), "avx2");
  const std::vector<InstructionSet> avx512 = {{"avx2", true}, {"fma", true}, {"avx512f", false}};
  EXPECT_STREQ(first_missing_instruction_set(avx512), "avx512f");
}

TEST(InstructionSets, ACpuWithEveryCompiledExtensionPasses) {
  const std::vector<InstructionSet> compiled = {{"sse2", true}, {"avx", true}, {"avx2", true}};
  EXPECT_EQ(first_missing_instruction_set(compiled), nullptr);
  EXPECT_EQ(first_missing_instruction_set({}), nullptr);  // a portable build requires nothing
}

TEST(InstructionSets, MessageIsOneLineNamingTheExtensionAndTheRebuild) {
  char message[512];
  missing_instruction_set_message("raylab", "avx2", message, sizeof(message));
  const std::string m = message;
  EXPECT_THAT(m, ::testing::StartsWith("raylab: error: "));
  EXPECT_THAT(m, HasSubstr("lacks avx2"));
  EXPECT_THAT(m, HasSubstr("-DRAYLAB_NATIVE=OFF"));
  EXPECT_EQ(m.find('\n'), std::string::npos);
  EXPECT_LT(m.size(), sizeof(message) - 1);  // not cut short
}

// The tests run where they were built, so this CPU has everything the build uses; and the
// list follows the compiler's macros.
TEST(InstructionSets, ThisCpuRunsThisBuild) {
  const auto compiled = compiled_instruction_sets();
  EXPECT_EQ(first_missing_instruction_set(compiled), nullptr);
  const auto listed = [&](const char* name) {
    for (const InstructionSet& s : compiled)
      if (std::strcmp(s.name, name) == 0) return true;
    return false;
  };
#if defined(__x86_64__)
  EXPECT_TRUE(listed("sse2"));
#endif
#ifdef __AVX2__
  EXPECT_TRUE(listed("avx2"));
#else
  EXPECT_FALSE(listed("avx2"));
#endif
#ifdef __AVX512F__
  EXPECT_TRUE(listed("avx512f"));
#else
  EXPECT_FALSE(listed("avx512f"));
#endif
}

}  // namespace
}  // namespace raylab
