#!/usr/bin/env bash
# AddressSanitizer + UndefinedBehaviorSanitizer build of the test suite
# (CMake option RAYLAB_SANITIZE: -O2 -g1), run through ctest. Any sanitizer
# report fails the run (UB reports are fatal: -fno-sanitize-recover). Called by
# .ci/run after `make test`. Built with clang: on a 2-core Zen 3 it compiles the
# instrumented wide-BVH kernels in half g++'s time. Not shared with
# scripts/fuzz.sh's build: the fuzzer's coverage hooks would slow the suite
# 2.3x, more than compiling the libraries twice costs.
# Usage: scripts/sanitize.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-asan}
jobs=${JOBS:-$(nproc 2>/dev/null || echo 2)}
bash scripts/install-deps.sh
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ -DRAYLAB_SANITIZE=ON >/dev/null
cmake --build "$build" -j "$jobs" --target raylab raylab_tests
# detect_leaks=0: TBB's and Embree's worker threads keep their (uninstrumented) pools until exit.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0:abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
ctest --test-dir "$build" --output-on-failure -j "$jobs" --timeout 900
echo "sanitize: ASan + UBSan test suite passed"
