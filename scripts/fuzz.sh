#!/usr/bin/env bash
# libFuzzer runs of bounded time: fuzz_mesh_load (mesh and scene files) and
# fuzz_rays (ray input against every accelerator), built with clang, ASan and
# UBSan (CMake option RAYLAB_FUZZ). Fails on any crash, sanitizer report,
# invariant violation or hang (-timeout). Called by .ci/run after `make test`.
# Usage: scripts/fuzz.sh [SECONDS_PER_TARGET (default 60)] [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
build=${2:-build-fuzz}
jobs=${JOBS:-$(nproc 2>/dev/null || echo 2)}
bash scripts/install-deps.sh
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER=clang++ -DRAYLAB_FUZZ=ON >/dev/null
cmake --build "$build" -j "$jobs" --target fuzz_mesh_load fuzz_rays

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Seeds: one small valid file per format (the first byte selects the format:
# 0 obj, 1 ply, 2 stl, 3 off, 4 gltf, 5 glb, 6 nff, 7 json scene).
mkdir -p "$work/mesh" "$work/rays" "$work/artifacts"
printf '\000v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' > "$work/mesh/obj"
printf '\001ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n' > "$work/mesh/ply"
printf '\002solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n' > "$work/mesh/stl"
printf '\003OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n' > "$work/mesh/off"
printf '\004{"asset":{"version":"2.0"},"meshes":[]}' > "$work/mesh/gltf"
printf '\006v\nfrom 0 0 5\nat 0 0 0\nup 0 1 0\nangle 45\nhither 1\nresolution 8 8\np 3\n0 0 0\n1 0 0\n0 1 0\n' > "$work/mesh/nff"
printf '\007{"meshes":[{"file":"input.obj"}],"camera":{"from":[0,0,5],"at":[0,0,0]}}' > "$work/mesh/json"
# Ray seeds: a ray into the scene, an axis-parallel one with -0 components, a negative tmin,
# and four rays this fuzzer found: a direction of 2^-148 (its reciprocal and margins overflow),
# an origin 2^50 away (the grids' walk lost a cell to rounding), hits beyond FLT_MAX, and an
# origin 2^104 away with |dir| = 0.003 (one rebase of the grids' walk still left it 2^51 out);
# and a pair that made Embree's stream API abort: a direction of 2^-82 beside a ray whose
# negative tmin moves its origin 7e14 away.
/usr/bin/python3 - "$work/rays" <<'PY'
import struct, sys
rays = [(0.5, 0.5, -1, 0, 0, 1, 0, float('inf')), (0.5, 0.5, -1, -0.0, -0.0, 1, 1e-3, float('inf')),
        (0.5, 0.5, 0.5, 0.3, -0.2, 0.9, -5, 5), (0, 0.5, 0.5, 1, 0, 0, 0, 0),
        (0.5, 0.5000035, -1, 0, 0, 2.0**-148, 2.0**-134, float('inf')),
        (float.fromhex('0x1.6p-138'), 0.5, -float.fromhex('0x1.001002p+50'), 0, 0, float.fromhex('0x1.01bap+0'),
         float.fromhex('0x1.000004p-126'), float('inf')),
        (float.fromhex('0x1.b6p-1'), 0.5, -float.fromhex('0x1.001p+104'), 0, 0, float.fromhex('0x1.fcp-128'), 0,
         float('inf')),
        (float.fromhex('0x1.fad8p-136'), float.fromhex('0x1.007ep-111'), -float.fromhex('0x1.01e7p+104'), 0, 0,
         float.fromhex('0x1.7fp-9'), 0, float('inf')),
        (-float.fromhex('0x1.2d2d2cp-82'),) * 8,
        (-float.fromhex('0x1.979796p+24'),) * 7 + (float.fromhex('0x1.00658p-132'),)]
open(sys.argv[1] + '/seed', 'wb').write(b''.join(struct.pack('<8f', *r) for r in rays))
PY
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
status=0
for target in fuzz_mesh_load fuzz_rays; do
  corpus="$work/${target#fuzz_}"
  [ "$target" = fuzz_mesh_load ] && corpus="$work/mesh"
  [ "$target" = fuzz_rays ] && corpus="$work/rays"
  echo "fuzz: $target for ${seconds}s"
  if ! "$build/$target" "$corpus" -max_total_time="$seconds" -timeout=30 -rss_limit_mb=4096 -max_len=4096 \
       -artifact_prefix="$work/artifacts/" -print_final_stats=1 2>"$work/$target.log"; then
    status=1
    tail -n 40 "$work/$target.log"
    mkdir -p out/fuzz && cp -r "$work/artifacts/." out/fuzz/ 2>/dev/null || true
    echo "fuzz: $target FAILED (reproducers copied to out/fuzz/)"
  else
    grep -E "stat::number_of_executed_units|Done" "$work/$target.log" | tail -n 2
  fi
done
[ $status -eq 0 ] && echo "fuzz: no failures"
exit $status
