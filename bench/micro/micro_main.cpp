// main() of raylab_microbench: Google Benchmark's, plus a word on its
// "***WARNING*** Library was built as DEBUG" line. Debian's libbenchmark
// package is compiled without NDEBUG, so the library prints that for every
// program; it concerns the harness's own bookkeeping. The kernels measured
// here are raylab's, compiled in this build's Release mode (-O3).
#include <cstdio>

#include <benchmark/benchmark.h>

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::AddCustomContext("raylab_kernels", "Release (-O3); a 'Library was built as DEBUG' warning refers to "
                                                 "Debian's libbenchmark package, not to the measured code");
  std::fprintf(stderr,
               "raylab_microbench: if Google Benchmark warns \"Library was built as DEBUG\", that is Debian's "
               "libbenchmark package (built without NDEBUG); raylab's kernels below are compiled Release (-O3).\n");
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
