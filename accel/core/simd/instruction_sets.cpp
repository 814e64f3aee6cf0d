#include "accel/core/simd/instruction_sets.h"

#include <cstdio>
#include <cstdlib>

// What runs before the check has passed is compiled for the x86-64 baseline
// (SSE2) whatever the build's flags: it must not use what it checks for.
// (GCC only: clang keeps the build's extensions in such a function; clang
// builds raylab for the checking builds, which run where they were built.)
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define RAYLAB_BASELINE_CODE __attribute__((target("arch=x86-64")))
#else
#define RAYLAB_BASELINE_CODE
#endif

namespace raylab {

namespace {

// Plain pointers here: a library template (std::span) called from a
// baseline function would not be inlined and would run the build's code.
struct Sets {
  const InstructionSet* first;
  size_t count;
};

RAYLAB_BASELINE_CODE Sets compiled_sets() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();  // may run before the runtime's own initialisers
#define RAYLAB_ISA(name) InstructionSet{name, __builtin_cpu_supports(name) != 0}
  static const InstructionSet sets[] = {
#ifdef __SSE2__
      RAYLAB_ISA("sse2"),
#endif
#ifdef __SSE3__
      RAYLAB_ISA("sse3"),
#endif
#ifdef __SSSE3__
      RAYLAB_ISA("ssse3"),
#endif
#ifdef __SSE4_1__
      RAYLAB_ISA("sse4.1"),
#endif
#ifdef __SSE4_2__
      RAYLAB_ISA("sse4.2"),
#endif
#ifdef __POPCNT__
      RAYLAB_ISA("popcnt"),
#endif
#ifdef __AES__
      RAYLAB_ISA("aes"),
#endif
#ifdef __PCLMUL__
      RAYLAB_ISA("pclmul"),
#endif
#ifdef __AVX__
      RAYLAB_ISA("avx"),
#endif
#ifdef __AVX2__
      RAYLAB_ISA("avx2"),
#endif
#ifdef __FMA__
      RAYLAB_ISA("fma"),
#endif
#ifdef __BMI__
      RAYLAB_ISA("bmi"),
#endif
#ifdef __BMI2__
      RAYLAB_ISA("bmi2"),
#endif
#if defined(__F16C__) && !defined(__clang__)  // names clang's __builtin_cpu_supports does not know
      RAYLAB_ISA("f16c"),
#endif
#if defined(__LZCNT__) && !defined(__clang__)
      RAYLAB_ISA("lzcnt"),
#endif
#if defined(__MOVBE__) && !defined(__clang__)
      RAYLAB_ISA("movbe"),
#endif
#ifdef __AVX512F__
      RAYLAB_ISA("avx512f"),
#endif
#ifdef __AVX512CD__
      RAYLAB_ISA("avx512cd"),
#endif
#ifdef __AVX512VL__
      RAYLAB_ISA("avx512vl"),
#endif
#ifdef __AVX512BW__
      RAYLAB_ISA("avx512bw"),
#endif
#ifdef __AVX512DQ__
      RAYLAB_ISA("avx512dq"),
#endif
#ifdef __AVX512VBMI__
      RAYLAB_ISA("avx512vbmi"),
#endif
#ifdef __AVX512VNNI__
      RAYLAB_ISA("avx512vnni"),
#endif
  };
#undef RAYLAB_ISA
  return {sets, sizeof(sets) / sizeof(sets[0])};
#else
  return {nullptr, 0};
#endif
}

RAYLAB_BASELINE_CODE const char* first_missing(const InstructionSet* sets, size_t count) {
  for (size_t i = 0; i < count; ++i)
    if (!sets[i].on_cpu) return sets[i].name;
  return nullptr;
}

}  // namespace

std::span<const InstructionSet> compiled_instruction_sets() {
  const Sets s = compiled_sets();
  return {s.first, s.count};
}

const char* first_missing_instruction_set(std::span<const InstructionSet> compiled) {
  return first_missing(compiled.data(), compiled.size());
}

RAYLAB_BASELINE_CODE void missing_instruction_set_message(const char* program, const char* missing, char* out,
                                                          size_t size) {
  std::snprintf(out, size,
                "%s: error: this CPU lacks %s, which this binary was compiled to use (-march=native on the machine "
                "that built it); rebuild on this machine, or configure with -DRAYLAB_NATIVE=OFF for a binary that "
                "runs on any x86-64 CPU",
                program, missing);
}

RAYLAB_BASELINE_CODE void exit_unless_cpu_runs_this_binary(const char* program) {
  const Sets compiled = compiled_sets();
  const char* missing = first_missing(compiled.first, compiled.count);
  if (missing == nullptr) return;
  char message[512];
  missing_instruction_set_message(program, missing, message, sizeof(message));
  std::fprintf(stderr, "%s\n", message);
  std::_Exit(2);
}

}  // namespace raylab
