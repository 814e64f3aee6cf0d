#pragma once
// The one instruction-set check of a binary. Every vector kernel (the wide
// BVH's, the SIMD triangle blocks of the k-d tree, BSP, grids and octrees;
// simd.h) and whatever else the compiler vectorised use the instruction sets
// the build was compiled for (RAYLAB_NATIVE=ON: -march=native on the machine
// that built it). On a CPU without one of them the binary would stop on an
// illegal instruction somewhere in a kernel; exit_unless_cpu_runs_this_binary(),
// run before the program's other initialisers (app/main.cpp), stops it with
// one line instead.
#include <cstddef>
#include <span>

namespace raylab {

// An x86 instruction-set extension this build may use, named as the
// compiler's -m option and __builtin_cpu_supports name it, and whether the
// running CPU has it.
struct InstructionSet {
  const char* name;
  bool on_cpu;
};

// The extensions this build may use (the compiler's predefined macros, e.g.
// __AVX2__), oldest first; empty off x86.
std::span<const InstructionSet> compiled_instruction_sets();

// The first of `compiled` the CPU lacks, or nullptr.
const char* first_missing_instruction_set(std::span<const InstructionSet> compiled);

// The one-line message (no newline) for the extension `missing`, written to
// out[0..size).
void missing_instruction_set_message(const char* program, const char* missing, char* out, size_t size);

// When the CPU lacks an extension the build uses: the message on stderr, then
// exit status 2.
void exit_unless_cpu_runs_this_binary(const char* program);

}  // namespace raylab
